#!/usr/bin/env bash
# Release 5 candidates on one GPU host (16 cores): three stage-2 recipes trained side by side on one
# GPU from one procedural build with twice release 4's scenes (3,000), differing only in the look of
# the real training images (RUNS="v23:$c/real_train_v2,$c/real_train_v3" adds both looks at once). Real shards are imported on a CPU machine (the pool cannot travel):
#   TR=$(python3 scripts/real_split.py ../shared/real_train/partnet_mobility --print train)
#   v2 (release 4's): jax3dc data import $TR --out .carry/real_train_v2 --split train --views 8 --augment \
#       --mirror --palette-per-view --size 224
#   v3: the same with --appearance varied (random lights, sky / floor, jittered part colours and textures,
#       camera distance and field of view per view) -> .carry/real_train_v3
#   held-out fifth and fixtures as in docs/runs/release3_20261128/run.sh.
# A call carries at most 64 MiB, so `run.sh split` (CPU machine) cuts each shard folder into parts
# under .carry/parts/<name>.<k>/ of at most PART_MB; `run.sh setup` (GPU host) joins the parts each call
# brings into $R/carry/<name>/ (they stay on the machine for the next calls).
# Every call copies the working tree afresh onto the host, so a process that outlives its call and imports
# lazily can meet a half-copied tree ("No module named data_pipeline.loader" killed candidate v3 in the
# first attempt): build and start run from a snapshot of the tree in $R/src.
# Usage: run.sh split NAME... | setup | build | start | wait MINUTES | pack OUTDIR
set -uo pipefail
R=/tmp/r5
export MUJOCO_GL=egl PYTHONUNBUFFERED=1 PYTHONPATH=$R/site LD_LIBRARY_PATH=$R/gl/usr/lib/x86_64-linux-gnu:${LD_LIBRARY_PATH:-}
snapshot() {  # one copy of the tree per host, taken by the first of build / start, run from there after
  [ -d $R/src ] || { mkdir -p $R/src && tar cf - --exclude=./.git --exclude=./.carry --exclude=./.whl --exclude=./.gl . \
      | tar xf - -C $R/src; }
  cd $R/src
}
case "$1" in
split)  # run.sh split NAME... : .carry/NAME -> .carry/parts/NAME.0, NAME.1, ...
  shift; mkdir -p .carry/parts
  for name in "$@"; do
    d=.carry/$name; rm -rf .carry/parts/$name.*
    k=0; used=0; mkdir -p .carry/parts/$name.$k; cp "$d/manifest.json" .carry/parts/$name.$k/
    for f in "$d"/*.array_record; do
      size=$(stat -c %s "$f")
      if [ $(( used + size )) -gt $(( ${PART_MB:-40} * 1048576 )) ]; then k=$((k + 1)); used=0; mkdir -p .carry/parts/$name.$k; fi
      cp "$f" .carry/parts/$name.$k/; used=$(( used + size ))
    done
  done
  du -sh .carry/parts/* ;;
setup)
  mkdir -p $R/carry
  for d in .carry/parts/*/; do
    [ -d "$d" ] || continue
    name=$(basename "$d"); name=${name%.*}; mkdir -p $R/carry/$name; cp "$d"/* $R/carry/$name/
  done
  # the carried wheels (scripts/gpu_carry.sh) not installed yet, in one pip call: wheels that share a
  # package folder (mujoco, mujoco-core) must be installed together; $R/site/.wheels lists those done
  new=(); for w in .whl/*.whl; do grep -qxF "${w##*/}" $R/site/.wheels 2>/dev/null || new+=("$w"); done
  if [ ${#new[@]} -gt 0 ]; then
    pip install -q --no-deps --target $R/site "${new[@]}" 2>&1 | grep -v "as the 'root' user"
    [ "${PIPESTATUS[0]}" -eq 0 ] && printf '%s\n' "${new[@]##*/}" >> $R/site/.wheels
  fi
  # the `jax3dc` subcommands are entry points: without installing the project, a dist-info on the path names them
  mkdir -p $R/site/jax3dc-0.dist-info && printf 'Metadata-Version: 2.1\nName: jax3dc\nVersion: 0\n' > $R/site/jax3dc-0.dist-info/METADATA
  sed -n '/^\[project.entry-points."jax3dc.commands"\]/,/^$/p' pyproject.toml | sed 's/^\[project.entry-points."\(.*\)"\]/[\1]/; s/"//g' \
      > $R/site/jax3dc-0.dist-info/entry_points.txt
  [ -d $R/gl ] || for d in .gl/*.deb; do dpkg -x "$d" $R/gl; done  # GLVND's libEGL: the image has none
  du -sh $R/carry/* ;;
build)
  snapshot
  ( python3 -m jax3dc.cli data build --out $R/data --objects 8500 --scenes ${SCENES:-3000} --views 2 \
        --augment --size 224 --appearance varied --workers 16 --quiet > $R/build.log 2>&1; echo built >> $R/build.log
  ) < /dev/null > /dev/null 2>&1 &
  disown; echo "build started" ;;
start)
  snapshot
  export XLA_PYTHON_CLIENT_MEM_FRACTION=0.25
  while ! grep -q built $R/build.log 2>/dev/null; do sleep 5; done
  c=$R/carry
  common="--init mini --tokenizer jax3dc/release --objects 8500 --scenes ${SCENES:-3000} --views 2 --augment --appearance varied
          --heldout $c/real_heldout --fixtures $c/fixtures --pivot-frame box --steps ${STEPS:-1400} --lr 1e-3
          --eval-records 300 --eval-batch 64 --budget-min ${BUDGET:-24} --reserve-min 6 --set loader_workers=3"
  for run in ${RUNS:-v2:$c/real_train_v2 v3:$c/real_train_v3}; do
    IFS=: read name real <<< "$run"
    mkdir -p $R/$name && ln -sfn $R/data $R/$name/data
    extra=""; [ "$name" = v2 ] && extra="--compare jax3dc/release"
    setsid nohup python3 -m recipes.release_model --out $R/$name $common --real $real --real-weight 0.3 \
        $extra > $R/$name.log 2>&1 < /dev/null &
  done
  sleep 5; tail -n 2 $R/*.log ;;
wait)
  end=$(( $(date +%s) + ${2:-9} * 60 ))
  while [ $(date +%s) -lt $end ]; do
    if ! pgrep -f "recipes.release_model" >/dev/null; then echo "all runs ended"; break; fi
    sleep 15
  done
  for f in $R/*.log; do echo "== $f"; grep -v "^\s*$" $f | tail -n 3 | cut -c1-300; done
  nvidia-smi --query-gpu=utilization.gpu,memory.used --format=csv ;;
pack)
  for name in v2 v3 v23; do
    [ -d $R/$name ] || continue
    tar czf $2/$name.tgz -C $R/$name --exclude='sets' --exclude='*.png' --exclude='index.html' --exclude='viewers' \
        release summary.json bench train/metrics.jsonl 2>/dev/null
    cp $R/$name.log $2/ 2>/dev/null
  done
  cp $R/build.log $2/ 2>/dev/null
  ls -la $2 ;;
esac
