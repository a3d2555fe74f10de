"""The `jax3dc` command renders on a machine without a display even when MUJOCO_GL is unset.

MuJoCo reads MUJOCO_GL once, at its first import; the command's parser imports modules that
import mujoco (the physics checks), so the headless choice must be made before them.
"""

import os
import subprocess
import sys


def test_data_build_renders_without_display_or_mujoco_gl(tmp_path):
    env = {k: v for k, v in os.environ.items() if k not in ("MUJOCO_GL", "PYOPENGL_PLATFORM", "DISPLAY")}
    out = tmp_path / "data"
    r = subprocess.run([sys.executable, "-m", "jax3dc.cli", "data", "build", "--out", str(out), "--objects", "1",
                        "--views", "1", "--size", "32", "--quiet"],
                       env=env, capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stderr[-2000:]
    assert list(out.glob("*.array_record")), "no shard written"


def test_a_script_that_imports_evaluation_before_the_renderer_still_renders():
    """A benchmark imports eval (which imports mujoco) long before it renders: importing the package
    must already have chosen the headless backend."""
    env = {k: v for k, v in os.environ.items() if k not in ("MUJOCO_GL", "PYOPENGL_PLATFORM", "DISPLAY")}
    script = ("import eval.pixels, mujoco\n"
              "m = mujoco.MjModel.from_xml_string('<mujoco><worldbody><geom size=\"0.1\"/></worldbody></mujoco>')\n"
              "r = mujoco.Renderer(m, 16, 16)\n"
              "r.update_scene(mujoco.MjData(m))\n"
              "assert r.render().shape == (16, 16, 3)\n")
    r = subprocess.run([sys.executable, "-c", script], env=env, capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stderr[-2000:]


def test_headless_backend_is_one_the_machine_has(monkeypatch):
    """Under MUJOCO_GL=egl without libEGL, ``import mujoco`` itself fails (a bare GPU machine), so
    the backend follows the installed libraries, and without any the variable stays unset."""
    from jax3dc import gl

    for installed, expected in [({"EGL", "OSMesa"}, "egl"), ({"OSMesa"}, "osmesa"), (set(), None)]:
        monkeypatch.delenv("MUJOCO_GL", raising=False)
        monkeypatch.setattr(gl, "find_library", lambda name: f"lib{name}.so.1" if name in installed else None)
        assert gl.configure_gl() == expected
        assert os.environ.get("MUJOCO_GL") == expected
    monkeypatch.setenv("MUJOCO_GL", "glfw")  # the caller's choice is kept
    assert gl.configure_gl() == "glfw"


def test_rendering_without_an_opengl_context_says_what_to_install(tmp_path):
    """GLFW without a display cannot make a context: one line naming the backend and the fix,
    exit 1, no traceback (MuJoCo's own message speaks of mjr_makeContext)."""
    env = {k: v for k, v in os.environ.items() if k not in ("PYOPENGL_PLATFORM", "DISPLAY")}
    env["MUJOCO_GL"] = "glfw"
    r = subprocess.run([sys.executable, "-m", "jax3dc.cli", "data", "build", "--out", str(tmp_path / "data"),
                        "--objects", "1", "--views", "1", "--size", "32", "--quiet"],
                       env=env, capture_output=True, text=True, timeout=600)
    assert r.returncode == 1
    assert "cannot render: no OpenGL context with MUJOCO_GL=glfw" in r.stderr and "scripts/setup.sh" in r.stderr
    assert "Traceback" not in r.stderr
