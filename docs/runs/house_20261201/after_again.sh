#!/bin/bash
# Repeat the "after" side of the issue-48 check at any commit of main, in a fresh worktree:
#   1. eval/evaluators/physics_ground_truth.py --seeds 1 (all categories + the 9 PartNet-Mobility fixtures, C backend, 1 worker)
#   2. jax3dc eval run on the test split of /tmp/house/build (204 records, made by the 6ac563d code)
#      with --checkpoint /tmp/house/release2 (release 2 as shipped at 6ac563d), default decoding
# then compares both with the "before" (6ac563d) outputs using the same comparison scripts.
# usage: bash /tmp/house/after_again.sh COMMIT [LIMIT]    (LIMIT: eval records, default 0 = all 204)
# outputs: /tmp/house/again/<short>_<stamp>/{worktree,verdicts.jsonl,details.jsonl,gt.log,eval/,eval.log,*_compare.txt}
set -u
commit=${1:?usage: after_again.sh COMMIT [LIMIT]}
limit=${2:-0}
H=/tmp/house
short=$(git -C /work/main rev-parse --short=7 "$commit^{commit}") || exit 1
run=$H/again/${short}_$(date +%Y%m%d-%H%M%S)
wt=$run/worktree
mkdir -p "$run"
for need in $H/build/manifest.json $H/release2/model.safetensors $H/before_verdicts.jsonl $H/eval_before/predictions.jsonl; do
  [ -e "$need" ] || { echo "missing $need (made by the issue-48 check; see /work/main/docs/runs/house_20261201/commands.sh)"; exit 1; }
done
git -C /work/main worktree add --detach "$wt" "$commit" || exit 1
cd "$wt" || exit 1
export PYTHONPATH=$wt MUJOCO_GL=egl
echo "commit $(git rev-parse HEAD) -> $run"
python3 -c 'import jax3dc; print("jax3dc from", jax3dc.__file__)' | tee "$run/import.txt"

t=$(date +%s)
nice -n 5 python3 -m eval.evaluate physics_ground_truth --seeds 1 --fixtures /work/shared/fixtures/partnet_mobility \
  --verdicts "$run/verdicts.jsonl" --details "$run/details.jsonl" 2>&1 | tee "$run/gt.log"
echo "physics wall_s $(( $(date +%s) - t )) rc ${PIPESTATUS[0]}" | tee -a "$run/gt.log"

t=$(date +%s)
python3 -c 'import sys; from jax3dc.cli import main; sys.exit(main())' eval run --data $H/build --split test \
  --limit "$limit" --checkpoint $H/release2 --out "$run/eval" 2>&1 | tee "$run/eval.log"
echo "eval wall_s $(( $(date +%s) - t )) rc ${PIPESTATUS[0]}" | tee -a "$run/eval.log"

cd $H
python3 scripts/compare_verdicts_exact.py before_verdicts.jsonl "$run/verdicts.jsonl" | tee "$run/verdicts_compare.txt"
if cmp -s before_details.jsonl "$run/details.jsonl"; then echo "details: byte-identical"; else echo "details: DIFFERENT"; diff before_details.jsonl "$run/details.jsonl"; fi | tee "$run/details_compare.txt"
diff before_gt_summary.txt <(sed 's/\r/\n/g' "$run/gt.log" | grep -v "objects:") | tee "$run/gt_summary_diff.txt"
if [ "$limit" = 0 ]; then
  python3 scripts/compare_eval.py eval_before "$run/eval" | tee "$run/eval_compare.txt"
else
  echo "LIMIT=$limit: compare with a before run of the same --limit (eval_before has all 204)"
  python3 scripts/compare_eval.py eval_before "$run/eval" | tee "$run/eval_compare.txt"
fi
echo "done: $run"
