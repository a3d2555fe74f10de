"""Runs ``python -m jax3dc.cli ARGS...`` under an address-space limit and writes the command's peak
resident memory (bytes) to a file: ``python measured.py LIMIT_BYTES REPORT_FILE ARGS...``.

The test runner cannot measure this itself: a child it forks starts with the runner's resident set,
and Linux keeps that high-water mark through exec (3 GiB in a full test run), so the command is
forked from this small process instead. Exits with the command's exit code.
"""

from __future__ import annotations

import os
import resource
import signal
import sys


def main() -> None:
    limit, report, args = int(sys.argv[1]), sys.argv[2], sys.argv[3:]
    pid = os.fork()
    if pid == 0:
        resource.setrlimit(resource.RLIMIT_AS, (limit, limit))
        os.execv(sys.executable, [sys.executable, "-m", "jax3dc.cli", *args])
    _, status, usage = os.wait4(pid, 0)
    with open(report, "w") as f:
        f.write(str(usage.ru_maxrss * 1024))
    code = os.waitstatus_to_exitcode(status)
    if code < 0:  # killed by a signal: end the same way
        signal.signal(-code, signal.SIG_DFL)
        os.kill(os.getpid(), -code)
    sys.exit(code)


if __name__ == "__main__":
    main()
