#!/usr/bin/env bash
# Issue 51's one-GPU figures on one GPU host (16 cores), in one chain started detached (setsid):
#   layers   bench/layer_storage.py for each layout of the 4B decoder (cold compile, tokens/s)
#   fit      `jax3dc train` 4B, fp32 master + bf16 moments, remat=full, 4 rows of 4,096 in 4
#            micro-batches, the device pool capped at 80 GB (XLA_PYTHON_CLIENT_MEM_FRACTION), cold
#   scan     the same command with scan_layers=true (cold), for its compile split
#   prec     bench/master_precision.py on the 2B over a procedural build made here
# Usage (carry .whl .gl): run.sh setup | start [STAGES] | wait MINUTES | pack OUTDIR
# (start snapshots the tree and runs `chain` from the snapshot, detached: every device command copies the tree afresh)
set -uo pipefail
R=/tmp/t51
export PYTHONUNBUFFERED=1 PYTHONPATH=/tmp/r5/site MUJOCO_GL=egl LD_LIBRARY_PATH=/tmp/r5/gl/usr/lib/x86_64-linux-gnu:${LD_LIBRARY_PATH:-}
GPU_MEM_GB=${GPU_MEM_GB:-80}
case "$1" in
setup) bash docs/runs/release5_20261201/run.sh setup >/dev/null; nvidia-smi -L ;;
start)
  mkdir -p $R/out; [ -d $R/src ] || { mkdir -p $R/src && tar cf - --exclude=./.git --exclude=./.carry --exclude=./.whl \
      --exclude=./.gl . | tar xf - -C $R/src; }
  cd $R/src
  setsid nohup bash docs/runs/train_scale_20261202/run.sh chain "${2:-layers,fit,prec,scan}" > $R/chain.log 2>&1 < /dev/null &
  echo "started" ;;
chain)  # run.sh chain STAGES: the stages one after another (run from the snapshot)
  stages=$2
  total=$(nvidia-smi --query-gpu=memory.total --format=csv,noheader,nounits | head -1)  # MiB
  fraction=$(python3 -c "print(round($GPU_MEM_GB * 1e9 / ($total * 2**20), 3))")
  TRAIN="python3 bench/train_command.py --data synthetic --preset qwen3_vl_4b --seq 4096 --batch 4 --accum 4 --log-every 2 --save-every 1000 --set attention=cudnn --set compile_cache="
  for s in ${stages//,/ }; do
      echo "=== $s $(date +%T)"
      case $s in
      layers) for l in list list_scan stacked_scan stacked_loop; do
                timeout 240 python3 bench/layer_storage.py --preset qwen3_vl_4b --layout $l --json $R/out/layers.jsonl 2>&1 | grep -v Warning | tail -3
              done ;;
      fit)  XLA_PYTHON_CLIENT_MEM_FRACTION=$fraction timeout 400 $TRAIN --steps 12 --set moments_dtype=bfloat16 \
                --out $R/fit --json $R/out/fit.jsonl > $R/out/fit.log 2>&1; echo "rc $? (pool fraction $fraction of $total MiB)"
            cp $R/fit/run/metrics.jsonl $R/out/fit_metrics.jsonl; tail -3 $R/out/fit.log ;;
      scan) timeout 300 $TRAIN --steps 8 --set moments_dtype=bfloat16 --set scan_layers=true \
                --out $R/scan --json $R/out/scan.jsonl > $R/out/scan.log 2>&1; echo "rc $?"
            cp $R/scan/run/metrics.jsonl $R/out/scan_metrics.jsonl; tail -2 $R/out/scan.log ;;
      prec) [ -f $R/data/manifest.json ] || python3 -m jax3dc.cli data build --out $R/data --objects 2000 --views 1 \
                --size 224 --workers 16 --quiet > $R/out/build.log 2>&1
            timeout 600 python3 bench/master_precision.py --data $R/data --preset qwen3_vl_2b \
                --settings fp32_master_fp32_moments,fp32_master_bf16_moments --out $R/prec --json $R/out/prec.jsonl \
                > $R/out/prec.log 2>&1; echo "rc $?"
            for d in $R/prec/*/; do cp $d/metrics.jsonl $R/out/prec_$(basename $d)_metrics.jsonl; done
            grep -v "WARNING\|it/s" $R/out/prec.log | tail -8 ;;
      esac
  done; echo "=== done $(date +%T)" ;;
wait)
  end=$(( $(date +%s) + 60 * $2 ))
  [ -f $R/chain.log ] || { echo "no chain on this machine (a fresh one: run setup and start again)"; exit 1; }
  while [ $(date +%s) -lt $end ] && ! grep -q "=== done" $R/chain.log; do sleep 10; done
  cat $R/chain.log ;;
pack) mkdir -p "$2"; cp $R/chain.log $R/out/; tar czf "$2/train_scale.tgz" -C $R/out . ; ls -la "$2" ;;
esac
