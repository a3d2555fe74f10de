#!/bin/bash
# usage: rescore.sh SIDE PREDICTIONS OUT -- score a predictions file with SIDE's code (no generation)
side=$1; pred=$2; out=$3
cd /tmp/house/$side || exit 1
export PYTHONPATH=/tmp/house/$side MUJOCO_GL=egl
python3 -c 'import sys; from jax3dc.cli import main; sys.exit(main())' eval run --data /tmp/house/build --split test \
  --limit 0 --predictions $pred --out $out 2>&1 | tail -12 | tee $out.log
