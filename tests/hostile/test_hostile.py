"""The hostile suite: every case runs the real `jax3dc` command in its own process, under a time
limit and an address-space limit, and must end with exit 1, exactly one stderr line naming the
problem, no traceback, nothing written outside its --out, and time and peak memory under the limits.

Cases run two at a time (CI has two cores); the case count, the limits and the slowest case are
printed (`pytest -s tests/hostile`).
"""

from __future__ import annotations

import os
import subprocess
import sys
import tempfile
import time
from collections import Counter
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

from tests.hostile.cases import Case, build_cases

TIME_LIMIT_S = 30.0
MEMORY_LIMIT_BYTES = 2 << 30
"""Address space of each command (virtual memory: a little above what importing the stack takes)."""
MIN_CASES = 150
WORKERS = 2
MEASURED = Path(__file__).with_name("measured.py")


def _files(root: Path) -> dict[str, tuple[int, int]]:
    """Every file under ``root`` (symbolic links not followed) with its size and modification time."""
    found = {}
    for folder, dirs, names in os.walk(root):
        for name in names + [d for d in dirs if os.path.islink(os.path.join(folder, d))]:
            path = os.path.join(folder, name)
            info = os.lstat(path)
            found[path] = (info.st_size, info.st_mtime_ns)
    return found


def _wait(pid: int, timeout: float) -> int | None:
    """Reap ``pid`` within ``timeout`` seconds, else kill its whole session; its exit code (None on a hang)."""
    deadline = time.perf_counter() + timeout
    while True:
        done, status = os.waitpid(pid, os.WNOHANG)
        if done:
            return os.waitstatus_to_exitcode(status)
        if time.perf_counter() > deadline:
            os.killpg(pid, 9)
            os.waitpid(pid, 0)
            return None
        time.sleep(0.02)


def _run(case: Case, cwd: Path) -> dict:
    env = {**os.environ, "PYTHONWARNINGS": "default"}  # a warning printed before the error line must show
    start = time.perf_counter()
    with tempfile.TemporaryDirectory() as tmp:
        err_path, report = Path(tmp) / "stderr", Path(tmp) / "peak"
        with err_path.open("wb") as err_file:
            process = subprocess.Popen([sys.executable, str(MEASURED), str(MEMORY_LIMIT_BYTES), str(report), *case.argv],
                                       cwd=cwd, env=env, stdout=subprocess.DEVNULL, stderr=err_file,
                                       start_new_session=True)
            rc = _wait(process.pid, TIME_LIMIT_S)
            process.returncode = rc if rc is not None else -9  # reaped here: Popen must not wait on it again
        seconds = time.perf_counter() - start
        err = err_path.read_bytes().decode(errors="replace")
        peak = int(report.read_text()) if report.exists() else 0
    if rc is None:
        return {"case": case, "hang": True, "seconds": TIME_LIMIT_S, "rc": None, "err": err, "peak": peak}
    return {"case": case, "hang": False, "seconds": seconds, "rc": rc, "err": err, "peak": peak}


def _problems(result: dict) -> list[str]:
    case, err = result["case"], result["err"].strip()
    problems = []
    if result["hang"]:
        problems.append(f"ran past {TIME_LIMIT_S:g} s")
    if result["rc"] != 1:
        problems.append(f"exit code {result['rc']}")
    if "Traceback" in err:
        problems.append("traceback")
    if "\n" in err or not err:
        problems.append(f"{len(err.splitlines())} stderr lines")
    # `validate` lists each problem of a document as "FILE: problem [rule]"; other commands say "jax3dc CMD: error:"
    own_format = case.argv[0] == "validate" and err.startswith(case.argv[1][:200])
    if not own_format and not (err.startswith("jax3dc ") and ": error: " in err):
        problems.append("not a jax3dc error line")
    if case.expect.lower() not in err.lower():
        problems.append(f"does not say {case.expect!r}")
    if len(err) > 1000:
        problems.append(f"{len(err)} characters")
    if result["peak"] > MEMORY_LIMIT_BYTES:
        problems.append(f"peak memory {result['peak'] >> 20} MiB")
    return problems


def test_hostile_inputs_fail_cleanly(tmp_path):
    root = tmp_path / "hostile"
    cases = build_cases(root)
    assert len(cases) >= MIN_CASES
    work = root / "cwd"
    work.mkdir()
    before = {p: v for p, v in _files(root).items() if not p.startswith(str(root / "out"))}
    start = time.perf_counter()
    with ThreadPoolExecutor(WORKERS) as pool:
        results = list(pool.map(lambda c: _run(c, work), cases))
    wall = time.perf_counter() - start
    after = {p: v for p, v in _files(root).items() if not p.startswith(str(root / "out"))}

    kinds = Counter(c.kind for c in cases)
    slowest = max(results, key=lambda r: r["seconds"])
    print(f"\nhostile suite: {len(cases)} cases ({', '.join(f'{k}: {n}' for k, n in sorted(kinds.items()))}); "
          f"limits {TIME_LIMIT_S:g} s and {MEMORY_LIMIT_BYTES >> 30} GiB address space per command; "
          f"{wall:.0f} s on {WORKERS} workers; slowest {slowest['case'].kind}/{slowest['case'].name} "
          f"{slowest['seconds']:.1f} s; largest peak resident memory {max(r['peak'] for r in results) >> 20} MiB")
    failures = [f"{r['case'].kind}/{r['case'].name}: {', '.join(p)} -- {r['err'].strip()[-300:]!r}"
                for r in results if (p := _problems(r))]
    assert not failures, f"{len(failures)} of {len(cases)} cases failed:\n" + "\n".join(failures)
    assert after == before, f"files written or changed outside --out: {sorted(set(after.items()) ^ set(before.items()))[:5]}"
