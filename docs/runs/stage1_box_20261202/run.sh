#!/usr/bin/env bash
# Stage-1 image network: the box-metric loss against the plain number loss, on one GPU host (16 cores).
# Builds: release 2's four (seeds 0-3, one view, so their 1,013 test objects stay the evaluation set)
# and EXTRA new two-view builds of NEW objects (seeds 4, 5, ...: view 1 with a joint moved). Then three
# candidates side by side on the one GPU, the same data for all:
#   a  from release 4, the plain number loss (more data alone)
#   b  from release 4, --number-weight 1 --box-weight 4 (train.stage1_box_metric)
#   c  from scratch (release 3's shape), the same loss as b
# The box metrics of builds 0-3 come computed (.s1box/metric.jsonl.gz: `python3 -m recipes.stage1_net
# --data runs/s1r2/data-0 ... data-3 --metrics-only --box-cache .s1box/metric.jsonl --box-workers 2`); the
# host computes the new builds' (`--metrics-only`, 15 processes) while a trains.
# Host setup (wheels, entry points, EGL): docs/runs/release5_20261201/run.sh setup.
#   d  from c, alone on the GPU, the same loss (`MINUTES=5.5 run.sh more`, once `all` has ended)
# Usage: [NEW=N EXTRA=K MINUTES=M] run.sh all | more | wait MINUTES | pack OUTDIR
# (a call brings back at most 8 files, so `pack` writes one tar of the candidates' folders and logs)
set -uo pipefail
R=/tmp/s1b
export MUJOCO_GL=egl PYTHONUNBUFFERED=1 PYTHONPATH=/tmp/r5/site LD_LIBRARY_PATH=/tmp/r5/gl/usr/lib/x86_64-linux-gnu:${LD_LIBRARY_PATH:-}
BUILDS="0:4000:1 1:7000:1 2:5000:1 3:4000:1 $(for k in $(seq 4 $((3 + ${EXTRA:-7}))); do echo -n "$k:${NEW:-3000}:2 "; done)"
me=docs/runs/stage1_box_20261202/run.sh
snapshot() {  # the host's tree may be rewritten while work runs: long-lived processes run from one copy of it
  [ -d $R/src ] || { mkdir -p $R/src && tar cf - --exclude=./.git --exclude=./.carry --exclude=./.whl --exclude=./.gl . \
      | tar xf - -C $R/src; }
  cd $R/src
}
train() {  # train NAME ARGS... : one candidate, detached (setsid) so it outlives the launching shell
  setsid nohup python3 -m recipes.stage1_net --out $R/$1 --data $data --image-size 128 --batch 256 --steps 60000 \
      --minutes ${MINUTES:-8} --hidden 512 --eval-limit 200 "${@:2}" > $R/$1.log 2>&1 < /dev/null &
}
case "$1" in
all)  # under setsid, so the work outlives the launching shell
  snapshot; mkdir -p $R; gunzip -c .s1box/metric.jsonl.gz > $R/metric.jsonl
  setsid nohup bash -c "$R/src/$me here" < /dev/null > $R/all.log 2>&1 &
  echo "all started" ;;
here)
  snapshot
  for b in $BUILDS; do
      IFS=: read seed n views <<< "$b"
      python3 -m jax3dc.cli data build --out $R/data-$seed --objects $n --seed $seed --scenes 0 --views $views \
          --size 128 --workers 16 --appearance varied --quiet >> $R/build.log 2>&1 && echo "built $seed $(date +%s)" >> $R/build.log
  done
  data=$(for b in $BUILDS; do echo -n "$R/data-${b%%:*} "; done)
  export XLA_PYTHON_CLIENT_MEM_FRACTION=0.28
  train a --init jax3dc/release/stage1 --lr 1e-3
  python3 -m recipes.stage1_net --out $R/m --data $data --metrics-only --box-cache $R/metric.jsonl --box-workers 15 \
      >> $R/build.log 2>&1
  cp $R/metric.jsonl $R/metric_c.jsonl  # each candidate appends to its own copy (nothing is left to compute)
  train b --init jax3dc/release/stage1 --lr 1e-3 --number-weight 1 --box-weight 4 --box-cache $R/metric.jsonl
  train c --widths 32 64 128 256 --blocks 2 --lr 2e-3 --number-weight 1 --box-weight 4 --box-cache $R/metric_c.jsonl
  echo "all started" >> $R/build.log ;;
more)
  snapshot
  data=$(for b in $BUILDS; do echo -n "$R/data-${b%%:*} "; done)
  train d --init $R/c/stage1 --lr 1e-3 --number-weight 1 --box-weight 4 --box-cache $R/metric_c.jsonl
  echo "more started" >> $R/build.log ;;
wait)
  end=$(( $(date +%s) + ${2:-9} * 60 ))
  while [ $(date +%s) -lt $end ]; do
    grep -q "all started" $R/build.log 2>/dev/null && ! pgrep -f "recipes.stage1_net" >/dev/null && { echo "all ended"; break; }
    sleep 10
  done
  tail -n 4 $R/build.log | cut -c1-300
  for f in $R/a.log $R/b.log $R/c.log $R/d.log; do [ -f $f ] && { echo "== $f"; tail -n 3 $f | cut -c1-400; }; done
  nvidia-smi --query-gpu=utilization.gpu,memory.used --format=csv,noheader ;;
pack)
  cd $R && tar cf $2/candidates.tar $(for n in a b c d; do [ -d $n/stage1 ] && echo "$n/stage1 $n/summary.json $n.log"; done) build.log
  ls -la $2 ;;
esac
