#!/usr/bin/env bash
# Release 4 candidates on one GPU host (16 cores): three stage-2 recipes trained side by side on one
# GPU from one procedural build (8,500 objects, 1,500 scenes), and the stage-1 image network beside
# them. Real shards are imported on a CPU machine (the pool cannot travel) and carried:
#   v1 (release 3's): jax3dc data import $(python3 scripts/real_split.py ../shared/real_train/partnet_mobility --print train) \
#       --out .carry/real_train --split train --views 4 --augment --size 224 --workers 2
#   v2: the same objects with --views 8 --augment --mirror --palette-per-view (every view of each
#       object's mirror image too, and S's colours permuted per view) -> .carry/real_train_v2
#   held-out fifth and fixtures as in docs/runs/release3_20261128/run.sh.
# Usage: run.sh setup | build | start | wait MINUTES | pack OUTDIR
set -uo pipefail
R=/tmp/r4
export MUJOCO_GL=egl PYTHONUNBUFFERED=1
case "$1" in
setup)  # carried data to $R/carry (it stays on the machine for the next calls)
  mkdir -p $R/carry
  for d in .carry/*; do [ -d "$d" ] && cp -r "$d" $R/carry/; done
  ls $R/carry ;;
build)  # procedural build for stage 2, two builds for stage 1, in the background
  mkdir -p $R
  ( python3 -m jax3dc.cli data build --out $R/data --objects 8500 --scenes 1500 --views 2 --augment --size 224 \
        --appearance varied --workers 16 --quiet > $R/build.log 2>&1
    for seed in 0 1; do
      python3 -m jax3dc.cli data build --out $R/s1/data-$seed --objects 20000 --seed $seed --scenes 0 --views 1 \
          --size 128 --appearance varied --workers 16 --quiet >> $R/build.log 2>&1
    done
    echo built >> $R/build.log ) < /dev/null > /dev/null 2>&1 &
  disown; echo "build started" ;;
start)  # three stage-2 candidates once the procedural build is complete; stage 1 once its builds are
  export XLA_PYTHON_CLIENT_MEM_FRACTION=0.2
  while ! grep -q '"complete": true' $R/data/manifest.json 2>/dev/null; do sleep 5; done
  common="--init mini --tokenizer jax3dc/release --objects 8500 --scenes 1500 --views 2 --augment --appearance varied
          --heldout $R/carry/real_heldout --fixtures $R/carry/fixtures --pivot-frame box --steps ${STEPS:-1500} --lr 1e-3
          --eval-records 300 --eval-batch 64 --budget-min ${BUDGET:-24} --reserve-min 6 --set loader_workers=3"
  for run in v2w3:real_train_v2:0.3 v2w5:real_train_v2:0.5 v1w3:real_train:0.3; do
    IFS=: read name real weight <<< "$run"
    mkdir -p $R/$name && ln -sfn $R/data $R/$name/data
    extra=""; [ "$name" = v2w3 ] && extra="--compare jax3dc/release"
    setsid nohup python3 -m recipes.release_model --out $R/$name $common --real $R/carry/$real --real-weight $weight \
        $extra > $R/$name.log 2>&1 < /dev/null &
  done
  ( while ! grep -q built $R/build.log 2>/dev/null; do sleep 5; done
    XLA_PYTHON_CLIENT_MEM_FRACTION=0.12 python3 -m recipes.stage1_net --out $R/s1 --data $R/s1/data-0 $R/s1/data-1 \
        --image-size 128 --widths 48 96 192 256 --hidden 384 --batch 128 --steps 40000 --minutes ${S1_MIN:-13} \
        > $R/s1.log 2>&1 ) < /dev/null > /dev/null 2>&1 &
  disown; sleep 5; tail -n 2 $R/*.log ;;
wait)
  end=$(( $(date +%s) + ${2:-9} * 60 ))
  while [ $(date +%s) -lt $end ]; do
    if ! pgrep -f "recipes.release_model|recipes.stage1_net" >/dev/null; then echo "all runs ended"; break; fi
    sleep 15
  done
  for f in $R/*.log; do echo "== $f"; grep -v "^\s*$" $f | tail -n 3 | cut -c1-300; done
  nvidia-smi --query-gpu=utilization.gpu,memory.used --format=csv ;;
pack)
  for name in v2w3 v2w5 v1w3; do
    [ -d $R/$name ] || continue
    tar czf $2/$name.tgz -C $R/$name --exclude='sets' --exclude='*.png' --exclude='index.html' release summary.json \
        bench train/metrics.jsonl 2>/dev/null
    cp $R/$name.log $2/ 2>/dev/null
  done
  [ -d $R/s1/stage1 ] && tar czf $2/s1.tgz -C $R/s1 stage1 summary.json test.jsonl 2>/dev/null
  cp $R/s1.log $R/build.log $2/ 2>/dev/null
  ls -la $2 ;;
esac
