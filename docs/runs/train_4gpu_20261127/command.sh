source .carry/prefix.sh
nvidia-smi -L > $OUT/gpus.txt
COMMON="--set data=.carry/real_train --set seq_len=8192 --set batch_size=16 --set grad_accum=4 --set steps=6 --set log_every=2 --set save_every=1000 --set keep_last=1 --set eval_batches=0 --set export_hf=false --set loader_workers=4 --set warmup_steps=5 --set remat=full --set attention=cudnn"
timeout 210 python3 -m jax3dc.cli train --init qwen3_vl_4b --output-dir /tmp/one $COMMON > $OUT/one.log 2>&1; echo rc $? >> $OUT/one.log
cp /tmp/one/metrics.jsonl $OUT/one_metrics.jsonl
for r in 0 1; do
  CUDA_VISIBLE_DEVICES=$((2*r)),$((2*r+1)) JAX_COORDINATOR_ADDRESS=localhost:12355 JAX_NUM_PROCESSES=2 JAX_PROCESS_ID=$r timeout 210 python3 -m jax3dc.cli train --init qwen3_vl_4b --output-dir /tmp/two $COMMON > $OUT/two_$r.log 2>&1 &
done
wait
echo done >> $OUT/two_0.log
cp /tmp/two/metrics.jsonl $OUT/two_metrics.jsonl
for f in $OUT/one.log $OUT/two_0.log $OUT/two_1.log; do echo == $f; grep -v "WARNING\|^I0000\|^W0000\|warp" $f | tail -4; done
python3 - <<'PY'
import json, os
out = os.environ["OUT"]
for name in ("one", "two"):
    try:
        rows = [json.loads(l) for l in open(f"{out}/{name}_metrics.jsonl")]
    except OSError as e:
        print(name, e); continue
    print(name, [(r.get("step"), round(r["loss"], 5) if "loss" in r else None, r.get("tokens_per_s"), r.get("mfu"), r.get("compile_s")) for r in rows])
PY
