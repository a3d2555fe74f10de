#!/bin/bash
# usage: run_eval.sh SIDE OUTDIR LIMIT  -- jax3dc eval run of worktree /tmp/house/SIDE on the build's test split with release 2
side=$1; out=$2; limit=$3
cd /tmp/house/$side || exit 1
export PYTHONPATH=/tmp/house/$side MUJOCO_GL=egl
start=$(date +%s)
python3 -c 'import sys; from jax3dc.cli import main; sys.exit(main())' eval run --data /tmp/house/build --split test \
  --limit $limit --checkpoint /tmp/house/release2 --out $out 2>&1 | tee $out.log
rc=${PIPESTATUS[0]}
echo "wall_s $(( $(date +%s) - start )) rc $rc" | tee -a $out.log
