#!/bin/bash
# Issue 48 check (2026-12-01, 2-core CPU): physics ground-truth verdicts and release 2's Table 1 on
# the procedural test split, before (6ac563d) and after (8706565). Exactly what was run, in order.
# The helper scripts it calls are the files of this folder (run_gt.sh, run_eval.sh, rescore.sh,
# timing_pair.sh, compare_*.py, after_again.sh), copied to /tmp/house first.
set -u
D=/work/main/docs/runs/house_20261201
H=/tmp/house
mkdir -p $H/logs $H/scripts
cp $D/run_gt.sh $D/run_eval.sh $D/after_again.sh $H/
cp $D/compare_verdicts_exact.py $D/compare_eval.py $D/compare_scores.py $D/rescore.sh $D/timing_pair.sh $H/scripts/
chmod +x $H/*.sh $H/scripts/*.sh
cd $H

# 1. worktrees; each side imports its own packages through PYTHONPATH
git -C /work/main worktree add --detach $H/before 6ac563d
git -C /work/main worktree add --detach $H/after 8706565
for s in before after; do (cd $H/$s && PYTHONPATH=$H/$s python3 -c 'import jax3dc; print(jax3dc.__file__)'); done

# 2. physics ground-truth bench, both sides at once, one core each (run_gt.sh SIDE CPU:
#    eval/evaluators/physics_ground_truth.py --seeds 1 --fixtures /work/shared/fixtures/partnet_mobility
#    --verdicts $H/SIDE_verdicts.jsonl --details $H/SIDE_details.jsonl, under taskset + nice -n 5).
#    --fixtures is explicit: the default resolves to /tmp/house/shared/... in a worktree (absent).
./run_gt.sh before 0 > logs/gt_before.out 2>&1 &
./run_gt.sh after 1 > logs/gt_after.out 2>&1 &
wait
python3 scripts/compare_verdicts_exact.py before_verdicts.jsonl after_verdicts.jsonl --digests verdict_digests.tsv | tee verdicts_compare.txt
python3 after/scripts/compare_verdicts.py before_verdicts.jsonl after_verdicts.jsonl | tee verdicts_compare_repo_tool.txt
cmp before_details.jsonl after_details.jsonl && echo "before_details.jsonl vs after_details.jsonl: byte-identical (cmp), $(wc -l < before_details.jsonl) lines, sha256 $(sha256sum < before_details.jsonl | cut -c1-64)" | tee details_compare.txt
sed 's/\r/\n/g' before_gt.log | grep -v "objects:" > before_gt_summary.txt
sed 's/\r/\n/g' after_gt.log | grep -v "objects:" > after_gt_summary.txt
diff before_gt_summary.txt after_gt_summary.txt > gt_summary_diff.txt

# 3. Table 1: release 2 (shipped at 6ac563d) as the checkpoint of both sides; one build by the before code
cp -r $H/before/jax3dc/release $H/release2
(cd $H/before && PYTHONPATH=$H/before MUJOCO_GL=egl python3 -m jax3dc.cli data build --out $H/build \
   --objects 4000 --views 1 --size 224 --seed 0 --appearance varied --workers 2 --quiet)   # demo's settings; 204 test records
# run_eval.sh SIDE OUT LIMIT: eval run --data $H/build --split test --limit LIMIT --checkpoint $H/release2 --out OUT
./run_eval.sh before $H/eval_before_l20 20                          # timing probe: 51 s for 20 records
./run_eval.sh before $H/eval_before 0 > logs/eval_before.out 2>&1   # all 204 test records
./run_eval.sh after  $H/eval_after  0 > logs/eval_after.out  2>&1
python3 scripts/compare_eval.py eval_before eval_after > eval_compare.txt

# 4. attribution
#  a) each side's predictions scored by the other side's code (eval run --predictions, no generation)
#     (a first try that also passed --checkpoint was refused: 'give at most one of --checkpoint, --predictions, ...')
scripts/rescore.sh after  $H/eval_before/predictions.jsonl $H/rescore_afterCode_beforePreds
scripts/rescore.sh before $H/eval_after/predictions.jsonl  $H/rescore_beforeCode_afterPreds
{ python3 scripts/compare_scores.py eval_before rescore_afterCode_beforePreds
  python3 scripts/compare_scores.py eval_after rescore_beforeCode_afterPreds; } | tee scoring_crosscheck.txt
#  b) generation at 52a5b9e (parent 6ac563d: the grammar-bounds commit alone on top of "before")
git -C /work/main worktree add --detach $H/at_52a5b9e 52a5b9e
./run_eval.sh at_52a5b9e $H/eval_at_52a5b9e 0 > logs/eval_at_52a5b9e.out 2>&1
python3 scripts/compare_eval.py eval_at_52a5b9e eval_after > eval_compare_52a5b9e_vs_after.txt
python3 scripts/compare_eval.py eval_before eval_at_52a5b9e > eval_compare_before_vs_52a5b9e.txt
#  c) decode speed under the same load: 20 records per side, concurrently, one core each
scripts/timing_pair.sh | tee timing_pair.txt

# 5. the repeatable "after" side at any commit (tested at 8706565)
bash $H/after_again.sh 8706565 > logs/after_again_8706565.out 2>&1

# 6. files for this folder
cp before_verdicts.jsonl after_verdicts.jsonl before_details.jsonl after_details.jsonl before_gt_summary.txt \
   after_gt_summary.txt verdicts_compare.txt verdicts_compare_repo_tool.txt details_compare.txt gt_summary_diff.txt \
   verdict_digests.tsv eval_compare.txt eval_compare_52a5b9e_vs_after.txt eval_compare_before_vs_52a5b9e.txt \
   scoring_crosscheck.txt timing_pair.txt $D/
cp eval_before/metrics.json $D/table1_before_metrics.json; cp eval_after/metrics.json $D/table1_after_metrics.json
cp eval_at_52a5b9e/metrics.json $D/table1_at_52a5b9e_metrics.json
cp eval_before/tables.md $D/table1_before_tables.md; cp eval_after/tables.md $D/table1_after_tables.md
cp build/manifest.json $D/build_manifest.json
python3 - <<'PY'
import json
keys = {"cabinet/cabinet_003000/0", "simple_bookcase/simple_bookcase_001798/0"}
with open("/work/main/docs/runs/house_20261201/differing_predictions.jsonl", "w") as f:
    for side in ("before", "after", "at_52a5b9e"):
        for l in open(f"/tmp/house/eval_{side}/predictions.jsonl"):
            r = json.loads(l)
            if r["key"] in keys:
                f.write(json.dumps({"side": side, **r}) + "\n")
PY
for s in before after at_52a5b9e; do sed 's/\r/\n/g' logs/eval_$s.out | grep -v "generating:" > $D/eval_${s}_log.txt; done
R=$(ls -d $H/again/8706565_* | head -1)
sed 's/\r/\n/g' logs/after_again_8706565.out | grep -v "objects:\|generating:" | grep -v "^  same" | cut -c1-220 > $D/after_again_test_8706565.txt
{ echo; echo "# reproducibility of the after side: the repeat at 8706565 against the first after run"
  python3 scripts/compare_eval.py eval_after $R/eval | grep -v "^  same"
  python3 scripts/compare_verdicts_exact.py after_verdicts.jsonl $R/verdicts.jsonl | tail -2; } >> $D/after_again_test_8706565.txt
cp $H/after_again.sh $D/
