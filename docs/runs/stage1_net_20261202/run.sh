#!/usr/bin/env bash
# Stage-1 image network, release 3 candidates, on one GPU host (16 cores): release 2's four builds
# again (same seeds and counts, so its 1,013 test objects are among the test objects) plus four new
# builds (seeds 4-7), then two networks trained side by side on the one GPU, each scored on every
# test record beside the shipped release 2 (`recipes.stage1_net --compare jax3dc/release/stage1`).
# Host setup (wheels, entry points, EGL) is release 5's: docs/runs/release5_20261201/run.sh setup.
# Usage: [NEW=N EXTRA=K VIEWS=V MINUTES=M] run.sh all | build | start | wait MINUTES | pack OUTDIR
# (release 3: NEW=3000 EXTRA=4 VIEWS=1 MINUTES=6.5)
set -uo pipefail
R=/tmp/s1
export MUJOCO_GL=egl PYTHONUNBUFFERED=1 PYTHONPATH=/tmp/r5/site LD_LIBRARY_PATH=/tmp/r5/gl/usr/lib/x86_64-linux-gnu:${LD_LIBRARY_PATH:-}
# EXTRA new builds (seeds 4, 5, ...) of NEW objects each; VIEWS 2 adds a view with one joint moved
BUILDS="0:4000 1:7000 2:5000 3:4000 $(for k in $(seq 4 $((3 + ${EXTRA:-4}))); do echo -n "$k:${NEW:-5000} "; done)"
snapshot() {  # the host's tree may be rewritten while work runs: long-lived processes run from one copy of it
  [ -d $R/src ] || { mkdir -p $R/src && tar cf - --exclude=./.git --exclude=./.carry --exclude=./.whl --exclude=./.gl . \
      | tar xf - -C $R/src; }
  cd $R/src
}
case "$1" in
build)  # under setsid: a process left in the launching shell's process group ends with that shell
  snapshot
  setsid nohup bash -c "$R/src/docs/runs/stage1_net_20261202/run.sh build-here" < /dev/null > /dev/null 2>&1 &
  echo "build started" ;;
build-here)
  snapshot
  for b in $BUILDS; do
      IFS=: read seed n <<< "$b"
      grep -q '"complete": true' $R/data-$seed/manifest.json 2>/dev/null && continue
      rm -rf $R/data-$seed
      python3 -m jax3dc.cli data build --out $R/data-$seed --objects $n --seed $seed --scenes 0 --views ${VIEWS:-1} --size 128 \
          --workers 16 --appearance varied --quiet >> $R/build.log 2>&1 && echo "built $seed $(date +%s)" >> $R/build.log
  done; echo "all built" >> $R/build.log ;;
all)  # builds, then trains, under setsid so both outlive the launching shell (run from the snapshot's copy)
  snapshot; me=$R/src/docs/runs/stage1_net_20261202/run.sh
  setsid nohup bash -c "$me build-here; $me start" < /dev/null > $R/all.log 2>&1 &
  echo "all started" ;;
start)  # run.sh start : waits for the builds, then trains both candidates at once
  snapshot
  while ! grep -q "all built" $R/build.log 2>/dev/null; do sleep 5; done
  data=$(for b in $BUILDS; do echo -n "$R/data-${b%%:*} "; done)
  common="--data $data --image-size 128 --batch 256 --lr 2e-3 --steps 60000 --minutes ${MINUTES:-8} --hidden 512
          --compare jax3dc/release/stage1"
  export XLA_PYTHON_CLIENT_MEM_FRACTION=0.4
  setsid nohup python3 -m recipes.stage1_net --out $R/a $common --widths 32 64 128 256 --blocks 2 > $R/a.log 2>&1 < /dev/null &
  setsid nohup python3 -m recipes.stage1_net --out $R/b $common --widths 48 96 192 384 --blocks 1 > $R/b.log 2>&1 < /dev/null &
  sleep 2; echo started ;;
wait)
  end=$(( $(date +%s) + ${2:-9} * 60 ))
  while [ $(date +%s) -lt $end ]; do
    pgrep -f "recipes.stage1_net|data build" >/dev/null || { echo "all ended"; break; }
    sleep 10
  done
  tail -n 3 $R/build.log; for f in $R/a.log $R/b.log; do [ -f $f ] && { echo "== $f"; tail -n 4 $f | cut -c1-400; }; done
  nvidia-smi --query-gpu=utilization.gpu,memory.used --format=csv,noheader ;;
pack)
  for name in a b; do
    [ -d $R/$name ] || continue
    mkdir -p $2/$name && cp -r $R/$name/stage1 $R/$name/summary.json $R/$name/test.jsonl $2/$name/ 2>/dev/null
    cp $R/$name.log $2/$name/train.log
  done
  cp $R/build.log $2/ ; ls -la $2 ;;
esac
