#!/usr/bin/env bash
# Issue 50's GPU figures on one GPU host (16 cores): bench/candidates_mjx.py over 200 factory
# objects, MJX on the GPU beside C MuJoCo with 16 workers in the same call, started detached.
# Usage (carry .whl .gl): run.sh setup | start [RECORDS] [EXTRA ARGS] | wait MINUTES | pack OUTDIR
set -uo pipefail
R=/tmp/c50
export PYTHONUNBUFFERED=1 PYTHONPATH=/tmp/r5/site MUJOCO_GL=egl LD_LIBRARY_PATH=/tmp/r5/gl/usr/lib/x86_64-linux-gnu:${LD_LIBRARY_PATH:-}
case "$1" in
setup) bash docs/runs/release5_20261201/run.sh setup >/dev/null; nvidia-smi -L ;;
start)
  rm -rf $R/src; mkdir -p $R/out $R/src
  tar cf - --exclude=./.git --exclude=./.carry --exclude=./.whl --exclude=./.gl . | tar xf - -C $R/src
  cd $R/src
  records=${2:-200}; shift 2 || shift $#
  setsid nohup python3 bench/candidates_mjx.py --records $records --workers 16 --out $R/out/candidates_mjx_$records.json "$@" \
      > $R/chain.log 2>&1 < /dev/null &
  echo "started" ;;
wait)
  end=$(( $(date +%s) + 60 * $2 ))
  [ -f $R/chain.log ] || { echo "no run on this machine (a fresh one: run setup and start again)"; exit 1; }
  while [ $(date +%s) -lt $end ] && ! grep -q '^}' $R/chain.log && pgrep -f candidates_mjx.py >/dev/null; do sleep 5; done
  grep -v "^ \|^{\|^}" $R/chain.log | tail -20 ;;
pack) mkdir -p "$2"; cp $R/chain.log $R/out/ 2>/dev/null; cp $R/out/* "$2"/; ls -la "$2" ;;
esac
