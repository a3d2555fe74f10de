"""Time of running the factories' part programs through the interpreter (the program stage of
`jax3dc data build` and of `jax3dc program run`), on one CPU core.

Run from the repository root:  python3 bench/program_run.py [--seeds 3] [--repeats 3]

Programs of every factory category at seeds 0..seeds-1 are generated first (that time is printed
on its own line: the factories' share of `data build`), then each
is run by `jax3dc.program.run_program` `repeats` times, and the least CPU time of the repeats
(process_time: other processes on a shared machine do not count) is summed over programs. To compare two versions of the interpreter, run this same file with PYTHONPATH set to the
other tree (the factories' programs must be the same text in both: the line `programs` prints a
digest of them).
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_var] = "1"

import argparse  # noqa: E402
import hashlib  # noqa: E402
import time  # noqa: E402

from jax3dc.factories import FACTORIES, generate_object  # noqa: E402
from jax3dc.program import run_program  # noqa: E402


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seeds", type=int, default=3, help="objects per category (seeds 0..N-1)")
    parser.add_argument("--repeats", type=int, default=3, help="runs per program; the fastest counts")
    args = parser.parse_args()
    for category in FACTORIES:  # imports and caches warm before timing
        generate_object(category, 100)
    start = time.process_time()
    texts = [generate_object(c, s).program_text for c in sorted(FACTORIES) for s in range(args.seeds)]
    generated = time.process_time() - start
    digest = hashlib.sha256("\n".join(texts).encode()).hexdigest()[:12]
    with_difference = sum("difference(" in t for t in texts)
    print(f"programs: {len(texts)} ({with_difference} with difference()), text digest {digest}")
    print(f"generate_object: {generated * 1e3 / len(texts):.2f} ms CPU per object (structure and program text)")
    total, triangles = 0.0, 0
    for text in texts:
        best = float("inf")
        for _ in range(args.repeats):
            start = time.process_time()
            result = run_program(text)
            best = min(best, time.process_time() - start)
        total += best
        triangles += sum(len(m.faces) for m in result.parts.values())
    print(f"run_program: {total * 1e3 / len(texts):.2f} ms per program, {len(texts) / total:.1f} programs/s, "
          f"{triangles} part triangles in all")


if __name__ == "__main__":
    main()
