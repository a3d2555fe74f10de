"""Issue 8's accuracy targets: false alarms on ground truth and mutation detection, in one command.

Ground truth is every factory category x ``--seeds`` seeds plus the PartNet-Mobility fixtures.
Printed: the false-alarm rate over joints (target <= 2%) with the reasons of the flagged joints,
the ground-truth objects whose whole verdict fails (a joint, rest interpenetration or the gravity
test; factory categories mounted in use are checked as mounted), and per mutation kind
(``eval.verdict_accuracy.mutations``) how many motion-changing mutations are flagged and flagged with an
expected reason (target >= 95% overall), and how many were skipped because the mutated joint sweeps
the same poses as the original. ``--details FILE`` writes one JSON line per flagged ground-truth
joint, failed ground-truth object and missed mutation, to find which check misses. ``--verdicts FILE``
writes each object's ground-truth verdict per joint, and its seconds, as soon as the object is done,
so a run cut short keeps what it finished.

CPU, a few minutes: python3 -m eval.evaluate physics_ground_truth --seeds 1 (--workers N: N processes; 3 seeds
take about 38 min on one core, 3 min with 16 workers). ``--backend mjx`` runs the same checks on MJX
(kinematics and rollouts), to compare its verdicts with C's: identical ``--details`` files mean the
same flagged joints and the same missed mutations; ``--verdicts`` files of the two backends compare
object by object over whatever both finished (``scripts/compare_verdicts.py``).
"""

from __future__ import annotations

import argparse
import contextlib
import functools
import json
import time
import warnings
from collections import Counter
from collections.abc import Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed
from pathlib import Path

from tqdm import tqdm

from eval.verdict_accuracy.ground_truth import (factory_objects, false_alarms, imported_objects,
                                               mutation_detection)
from jax3dc.factories import FACTORIES
from jax3dc.physics.findings import FAILURE, Finding, Verdict, describe

DEFAULT_FIXTURES = Path(__file__).resolve().parents[3] / "shared" / "fixtures" / "partnet_mobility"


def _measure(obj, mutations: bool, backend: str) -> tuple[dict, dict, list[str], list[str], str]:
    """One object's false alarms and mutation counts, its flagged joints (printed), detail lines and
    verdict line."""
    warnings.filterwarnings("ignore")
    flagged: list[str] = []
    details: list[str] = []
    verdicts: dict = {}
    t0 = time.perf_counter()

    def on_truth(obj, verdict: Verdict) -> None:
        verdicts.update(verdict=verdict.to_json(), seconds=round(time.perf_counter() - t0, 2))
        for part in verdict.joint_parts:
            reasons = verdict.joint_reasons(part, FAILURE)
            if reasons:
                flagged.append(f"  {obj.name} joint {part}: {'; '.join(reasons)}")
                details.append(json.dumps({"kind": "false alarm", "object": obj.name, "part": int(part),
                                           "reasons": reasons}))
        checks = verdict.object_reasons()
        whole = checks["rest"] + checks.get("gravity", [])
        if whole:  # object-level findings that fail the verdict
            flagged.append(f"  {obj.name} object: {'; '.join(whole)}")
            details.append(json.dumps({"kind": "object fails", "object": obj.name, "reasons": whole}))

    def on_mutation(obj, mutation, verdict: Verdict) -> None:
        failures = verdict.joint_findings(mutation.part, FAILURE)
        if not mutation.caught(failures):
            details.append(json.dumps({"kind": mutation.kind, "object": obj.name, "part": mutation.part,
                                       "reasons": [describe(f) for f in failures]}))

    truth = false_alarms([obj], on_truth, backend)
    per_kind = mutation_detection([obj], on_mutation, backend) if mutations else {}
    if backend == "mjx":  # each object's models compile anew: keep a worker's memory flat
        import jax  # lazy: jax (0.34 s) loads only in the mjx backend's workers; the C backend's never need it
        jax.clear_caches()
    line = json.dumps({"object": obj.name, "backend": backend, **verdicts})
    return truth, per_kind, flagged, details, line


def _heading(finding: Finding) -> str:
    """The summary's group of a flagged joint's finding: its reason up to the first " at ", where most
    reasons go on with the joint value (the groups the summary has always printed)."""
    return describe(finding).split(" at ")[0]


def main(argv: Sequence[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--seeds", type=int, default=1, help="seeds per factory category (default %(default)s)")
    parser.add_argument("--categories", default="", help="comma list of factory categories (default: all)")
    parser.add_argument("--fixtures", default=str(DEFAULT_FIXTURES),
                        help="folder of PartNet-Mobility objects (default %(default)s; '' for none)")
    parser.add_argument("--details", type=Path, help="write flagged ground-truth joints and missed mutations (JSON lines)")
    parser.add_argument("--verdicts", type=Path, help="write each object's ground-truth verdict as it finishes (JSON lines)")
    parser.add_argument("--no-mutations", action="store_true", help="false alarms only")
    parser.add_argument("--workers", type=int, default=1, help="objects checked in parallel processes (default %(default)s)")
    parser.add_argument("--backend", choices=("c", "mjx"), default="c",
                        help="simulator of the checks (default %(default)s; mjx compiles per object model)")
    args = parser.parse_args(argv)
    warnings.filterwarnings("ignore")

    categories = [c for c in args.categories.split(",") if c] or sorted(FACTORIES)
    if args.fixtures and not Path(args.fixtures).is_dir():  # a missing folder would drop the fixtures unseen
        parser.error(f"--fixtures {args.fixtures}: no such folder (pass --fixtures '' for factory objects only)")
    fixtures = sorted(d for d in Path(args.fixtures).iterdir() if d.is_dir()) if args.fixtures else []
    objects = list(factory_objects(categories, range(args.seeds))) + list(imported_objects(fixtures))
    t0 = time.perf_counter()
    measure = functools.partial(_measure, mutations=not args.no_mutations, backend=args.backend)
    results = []
    with contextlib.ExitStack() as stack:
        out = stack.enter_context(args.verdicts.open("w")) if args.verdicts else None
        if args.workers > 1:
            pool = stack.enter_context(ProcessPoolExecutor(args.workers))
            done = (f.result() for f in as_completed([pool.submit(measure, obj) for obj in objects]))
        else:
            done = map(measure, objects)
        for result in tqdm(done, total=len(objects), desc="objects", unit="object"):
            results.append(result)
            if out:
                out.write(result[-1] + "\n")
                out.flush()
    joints = sum(t["joints"] for t, *_ in results)
    flagged = sum(t["flagged"] for t, *_ in results)
    reasons = Counter(_heading(f) for t, *_ in results for f in t["findings"])
    print(f"\nfalse alarms: {flagged} of {joints} joints = {100 * flagged / max(joints, 1):.2f}% "
          f"(target <= 2%), {len(objects)} objects, {time.perf_counter() - t0:.0f} s with {args.workers} worker(s)")
    for reason, n in reasons.most_common():
        print(f"  {n:4d}  {reason}")
    failed = [name for t, *_ in results for name in t["objects_failed"]]
    print(f"objects whose verdict fails: {len(failed)} of {len(objects)} ({', '.join(sorted(failed)) or 'none'})")
    results.sort(key=lambda r: r[-1])  # completion order varies with the workers: print in object order
    print("\n".join(line for _, _, lines, _, _ in results for line in lines))
    if args.details:
        args.details.write_text("".join(line + "\n" for *_, lines, _ in results for line in lines))
    if args.no_mutations:
        return
    per_kind: dict[str, Counter] = {}
    for _, kinds, _, _, _ in results:
        for kind, counts in kinds.items():
            per_kind.setdefault(kind, Counter()).update(counts)
    print("\nmutation detection: flagged with the right reason, of the mutations that change the motion (target >= 95%)")
    print(f"  {'kind':26s} {'total':>6s} {'flagged':>8s} {'right':>6s} {'rate':>7s} {'skipped (same motion)':>22s}")
    sums = Counter()
    for kind in sorted(per_kind):
        c = per_kind[kind]
        sums.update(c)
        print(f"  {kind:26s} {c['total']:6d} {c['flagged']:8d} {c['right reason']:6d} "
              f"{100 * c['right reason'] / max(c['total'], 1):6.1f}% {c['skipped (same motion)']:22d}")
    print(f"  {'all':26s} {sums['total']:6d} {sums['flagged']:8d} {sums['right reason']:6d} "
          f"{100 * sums['right reason'] / max(sums['total'], 1):6.1f}% {sums['skipped (same motion)']:22d}")


if __name__ == "__main__":
    main()
