"""MJX internals are imported in one module, behind a version check with a clear error."""

from __future__ import annotations

import importlib
import subprocess
from importlib import metadata
from pathlib import Path

import pytest

from jax3dc.physics import mjx_private
from jax3dc.errors import SetupError

ROOT = Path(__file__).resolve().parents[2]


@pytest.mark.parametrize("version", ["3.16.2", "3.18.0", "4.0.0", "dev"])
def test_unsupported_versions_are_a_setup_error(version):
    with pytest.raises(SetupError, match=rf"mujoco-mjx {version} is not supported.*pip install 'mujoco-mjx>=3.17,<3.18'"):
        mjx_private.check_mjx_version(version)


def test_installed_version_is_supported_and_checked_on_import(monkeypatch):
    mjx_private.check_mjx_version(metadata.version("mujoco-mjx"))
    monkeypatch.setattr(metadata, "version", lambda name: "3.99.0")
    with pytest.raises(SetupError, match="3.99.0"):
        importlib.reload(mjx_private)
    monkeypatch.undo()
    importlib.reload(mjx_private)


def test_no_other_module_imports_mjx_internals():
    files = subprocess.run(["git", "grep", "--untracked", "-l", "-E", r"mjx\._src|mjx import _src", "--", "*.py"],
                           cwd=ROOT, capture_output=True, text=True).stdout.split()
    assert [f for f in files if not f.startswith("tests/")] == ["jax3dc/physics/mjx_private.py"]
