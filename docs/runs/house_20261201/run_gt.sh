#!/bin/bash
# usage: run_gt.sh SIDE CPU  -- physics ground-truth bench of worktree /tmp/house/SIDE on one core
side=$1; cpu=$2
cd /tmp/house/$side || exit 1
export PYTHONPATH=/tmp/house/$side MUJOCO_GL=egl
start=$(date +%s)
taskset -c $cpu nice -n 5 python3 -m eval.evaluate physics_ground_truth --seeds 1 \
  --fixtures /work/shared/fixtures/partnet_mobility \
  --verdicts /tmp/house/${side}_verdicts.jsonl --details /tmp/house/${side}_details.jsonl 2>&1 | tee /tmp/house/${side}_gt.log
rc=${PIPESTATUS[0]}
echo "wall_s $(( $(date +%s) - start )) rc $rc" | tee -a /tmp/house/${side}_gt.log
