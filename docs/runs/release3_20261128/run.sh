#!/usr/bin/env bash
# Release 3 candidates on one GPU host (16 cores), three recipes trained side by side on one GPU from
# the same procedural build: box-frame pivots with the real pool at 0.3 and 0.5 of examples, and
# absolute pivots at 0.3 (the ablation). Real shards: scripts/real_split.py's train part and held-out
# fifth, imported on a CPU machine:
#   jax3dc data import $(python3 scripts/real_split.py ../shared/real_train/partnet_mobility --print train) \
#       --out .carry/real_train --split train --views 4 --augment --size 224 --workers 2
#   jax3dc data import $(python3 scripts/real_split.py ../shared/real_train/partnet_mobility --print heldout) \
#       --out .carry/real_heldout --split test --views 2 --augment --size 224 --workers 2
#   jax3dc data import ../shared/fixtures/partnet_mobility/*/ --out .carry/fixtures --split test --views 2 --augment --size 224
# Usage: run.sh start | wait MINUTES | pack OUTDIR
set -uo pipefail
R=/tmp/r3
export MUJOCO_GL=egl PYTHONUNBUFFERED=1 XLA_PYTHON_CLIENT_MEM_FRACTION=0.22
case "$1" in
start)
  mkdir -p $R; ls -la .carry .carry/real_train | head -5
  [ -f $R/data/manifest.json ] || python3 -m jax3dc.cli data build --out $R/data --objects 8500 --scenes 600 --views 2 --augment --size 224 \
      --appearance varied --workers 16 --quiet 2>&1 | tail -3
  common="--init mini --tokenizer jax3dc/release --objects 8500 --scenes 600 --views 2 --augment --appearance varied
          --real $PWD/.carry/real_train --heldout $PWD/.carry/real_heldout --fixtures $PWD/.carry/fixtures --steps 1500 --lr 1e-3
          --eval-records 300 --eval-batch 256 --budget-min 20 --reserve-min 5 --set loader_workers=4"
  for run in box3:box:0.3 box5:box:0.5 abs3:absolute:0.3; do
    IFS=: read name frame weight <<< "$run"
    mkdir -p $R/$name && ln -sfn $R/data $R/$name/data
    extra=""; [ "$name" = box3 ] && extra="--compare jax3dc/release"
    setsid nohup python3 -m recipes.release_model --out $R/$name $common --pivot-frame $frame --real-weight $weight \
        $extra > $R/$name.log 2>&1 < /dev/null &
  done
  sleep 5; tail -n 2 $R/*.log ;;
wait)
  end=$(( $(date +%s) + ${2:-9} * 60 ))
  while [ $(date +%s) -lt $end ]; do
    if ! pgrep -f recipes.release_model >/dev/null; then echo "all runs ended"; break; fi
    sleep 20
  done
  for f in $R/*.log; do echo "== $f"; grep -v "^\s*$" $f | tail -n 4 | cut -c1-400; done
  nvidia-smi --query-gpu=utilization.gpu,memory.used --format=csv ;;
pack)
  for name in box3 box5 abs3; do
    [ -d $R/$name ] || continue
    tar czf $2/$name.tgz -C $R/$name --exclude='sets' --exclude='*.png' --exclude='index.html' release summary.json \
        bench train/metrics.jsonl 2>/dev/null
    cp $R/$name.log $2/ 2>/dev/null
  done
  ls -la $2 ;;
esac
