#!/usr/bin/env bash
# Release 6 candidates on one GPU host (16 cores): stage-2 recipes with no domain in the look, trained
# side by side on one GPU. What the CPU machine makes and carries (.carry/, git-ignored):
#   pool.tar.xz        the real pool converted (`jax3dc data convert` of each of its 328 objects, 30 MB
#                      against 482 MB of sources) and the 9 fixtures converted, with train.txt (the pool
#                      less its held-out fifth, `python3 scripts/real_split.py ... --print train`) and
#                      heldout.txt (the held-out fifth less door_8867, which release 4 trained on: the
#                      13 objects added 2026-12-05 moved it into the fifth; it trains here instead)
#   real_parts.tar.xz  ../shared/real_parts (737 PartNet cabinet part meshes) for composed objects
# Every source is rendered here, in the mixed look (each view plain or varied) for training, and the
# held-out fifth and the fixtures in both the plain and the varied look for scoring.
#   src.tar.gz         `git archive HEAD` without its weights: long work runs from this snapshot of the
#                      commit ($R/src, the weights copied in from the tree), never from the working tree a
#                      call copies afresh (half-written files met a lazy import once: release 5's v3)
# Usage: run.sh prepare (CPU machine) | setup | data proc|real | start | wait MINUTES | pack OUTDIR
set -uo pipefail
R=/tmp/r6
export MUJOCO_GL=egl PYTHONUNBUFFERED=1 PYTHONPATH=$R/site LD_LIBRARY_PATH=$R/gl/usr/lib/x86_64-linux-gnu:${LD_LIBRARY_PATH:-}
J="python3 -m jax3dc.cli"
snapshot() {
  [ -d $R/src ] || { mkdir -p $R/src && tar xzf $R/carry/src.tar.gz -C $R/src \
      && (cd jax3dc/release && find . -name '*.safetensors' -exec cp --parents {} $R/src/jax3dc/release/ \;); }
  cd $R/src
}
case "$1" in
prepare)  # on the CPU machine: .carry/pool.tar.xz, real_parts.tar.xz and src.tar.gz (about 38 MB, one call)
  P=$(mktemp -d); S=../shared
  for d in $S/real_train/partnet_mobility/*/; do jax3dc data convert "$d" --out $P/conv/$(basename "$d") --quiet; done
  for d in $S/fixtures/partnet_mobility/*/; do jax3dc data convert "$d" --out $P/fix/$(basename "$d") --quiet; done
  python3 scripts/real_split.py $S/real_train/partnet_mobility --print heldout | xargs -n1 basename \
      | grep -vx door_8867 > $P/heldout.txt
  (python3 scripts/real_split.py $S/real_train/partnet_mobility --print train | xargs -n1 basename; echo door_8867) \
      | sort > $P/train.txt
  mkdir -p .carry; tar cf - -C $P conv fix train.txt heldout.txt | xz -T2 -6 > .carry/pool.tar.xz
  tar cf - -C $S real_parts | xz -T2 -6 > .carry/real_parts.tar.xz
  git archive HEAD | tar --delete --wildcards '*.safetensors' | gzip -9 > .carry/src.tar.gz
  du -sh .carry/* ;;
setup)  # wheels (scripts/gpu_carry.sh), the jax3dc entry points, GLVND's EGL, and whatever .carry/ brings
  bash scripts/gpu_host_setup.sh $R; mkdir -p $R/carry
  for t in .carry/*.tar.xz; do [ -f "$t" ] && tar xJf "$t" -C $R/carry; done
  [ -f .carry/src.tar.gz ] && cp .carry/src.tar.gz $R/carry/
  ls $R/carry; du -sh $R/carry/* 2>/dev/null ;;
data)  # run.sh data proc | real: rendered in the background, in a process group of its own (the end of the
        # command that started it must not end it), from a copy of this script; each chain writes its markers to $R/done
  snapshot; cp "$OLDPWD/$0" $R/run.sh 2>/dev/null || cp "$0" $R/run.sh
  setsid nohup bash $R/run.sh _$2 < /dev/null > $R/data_$2.log 2>&1 &
  echo "data $2 started" ;;
_proc)  # 4,120 factory objects of seed 0 (about the 3,712 train objects the run's cut build held) and a
        # complete small build of seed 1 inside it (its val and test splits are what is scored)
  snapshot
  $J data build --out $R/data --objects 4120 --views 2 --augment --fuse-handles --appearance mixed \
      --size 224 --workers 16 --quiet && \
  $J data build --out $R/data/extra --seed 1 --objects 800 --scenes 100 --views 2 --augment --fuse-handles \
      --appearance mixed --size 224 --workers 16 --quiet && echo proc >> $R/done ;;
_real)
  snapshot; c=$R/carry
  $J data import $(sed "s|^|$c/conv/|" $c/train.txt) --out $R/real_train --split train --views 8 --augment \
      --mirror --palette-per-view --appearance mixed --size 224 --workers 16 --quiet
  for look in plain varied; do
    $J data import $(sed "s|^|$c/conv/|" $c/heldout.txt) --out $R/heldout_$look --split test --views 2 --augment \
        --appearance $look --size 224 --workers 16 --quiet
    $J data import $c/fix/* --out $R/fixtures_$look --split test --views 2 --augment --appearance $look --size 224 --quiet
  done
  echo real >> $R/done
  $J data build --out $R/composed --objects 0 --composed ${COMPOSED:-3000} --parts $c/real_parts --views 2 \
      --appearance mixed --size 224 --workers 16 --quiet && echo composed >> $R/done ;;
start)  # the candidate alone on the GPU (its loader needs the host's cores: with 3 loader workers each, three
        # candidates side by side waited on data 84 % of the time), then release 4 on the same records
  STEPS=${STEPS:-1500} setsid nohup bash $R/run.sh _train c3 "proc real composed" \
      "--init mini --lr 1e-3 --mix $R/composed=0.15 ${COMPARE:+--compare jax3dc/release}" < /dev/null > $R/c3.log 2>&1 &
  sleep 2; echo started ;;
_train)  # _train NAME MARKERS ARGS
  snapshot
  export XLA_PYTHON_CLIENT_MEM_FRACTION=0.7
  for m in $3; do while ! grep -qx $m $R/done 2>/dev/null; do sleep 5; done; done
  mkdir -p $R/$2 && ln -sfn $R/data $R/$2/data
  python3 -m recipes.release_model --out $R/$2 --tokenizer jax3dc/release --objects 4120 --scenes 0 --views 2 --augment \
      --appearance mixed --heldout $R/heldout_plain --heldout-varied $R/heldout_varied --fixtures $R/fixtures_plain \
      --fixtures-varied $R/fixtures_varied --pivot-frame box --steps $STEPS --real $R/real_train --real-weight 0.3 \
      --eval-records 300 --eval-batch 64 --budget-min 12 --reserve-min 3.5 --set loader_workers=14 $4 ;;
wait)
  end=$(( $(date +%s) + ${2:-9} * 60 ))
  while [ $(date +%s) -lt $end ]; do
    if ! pgrep -f "recipes.release_model|jax3dc.cli data" >/dev/null && grep -qx composed $R/done 2>/dev/null; then
      echo "all runs ended"; break; fi
    sleep 15
  done
  for f in $R/*.log; do echo "== $f"; grep -v "^\s*$" $f | tail -n 3 | cut -c1-300; done
  nvidia-smi --query-gpu=utilization.gpu,memory.used --format=csv ;;
pack)
  for name in c3; do
    [ -d $R/$name ] || continue
    tar czf $2/$name.tgz -C $R/$name --exclude='sets' --exclude='*.png' --exclude='index.html' --exclude='viewers' \
        release summary.json bench train/metrics.jsonl 2>/dev/null
    cp $R/$name.log $2/ 2>/dev/null
  done
  cp $R/data_*.log $R/done $2/ 2>/dev/null
  for d in $R/data $R/real_train $R/composed $R/heldout_plain; do
    [ -f $d/manifest.json ] && python3 -c "import json,sys; m=json.load(open('$d/manifest.json')); print('$d', sum(s['records'] for s in m['shards'].values()), 'records,', len(m.get('skipped', {})), 'skipped')"
  done
  ls -la $2 ;;
esac
