# Commands of the runs in this folder (2026-11-27). Each ran on a fresh GPU host with the project's
# packages installed; $OUT is the folder the results were written to; REAL_SHARDS is shards of the
# real training pool (jax3dc data import).

# ---- compile_a
B="python3 bench/train_step.py --preset qwen3_vl_4b --seq 4096 --batch 1 --attention cudnn --steps 8 --json $OUT/compile.jsonl"
run() { echo "=== $1 :: $2"; XLA_FLAGS="$2" timeout 200 $B $3 2>&1 | grep -E "compile:|step_s|mfu|peak|Error|error" | head -8; }
run default "" ""
run no_triton_gemm "--xla_gpu_enable_triton_gemm=false" ""
run autotune0 "--xla_gpu_autotune_level=0" ""

# ---- compile_b
B="python3 bench/train_step.py --preset qwen3_vl_4b --seq 4096 --batch 1 --attention cudnn --steps 8 --json $OUT/compile.jsonl"
run() { echo "=== $1 :: $2"; XLA_FLAGS="$2" timeout 200 $B $3 2>&1 | grep -E "compile:|step_s|mfu|peak|Error|error" | head -8; }
NT="--xla_gpu_enable_triton_gemm=false"
run llvm_parallel "$NT --xla_gpu_enable_llvm_module_compilation_parallelism=true" ""
run force16 "$NT --xla_gpu_force_compilation_parallelism=16" ""
run scan_min "$NT --xla_gpu_enable_llvm_module_compilation_parallelism=true" "--scan --remat minimal"

# ---- compile_c
B="python3 bench/train_step.py --preset qwen3_vl_4b --seq 4096 --batch 1 --attention cudnn --steps 8 --json $OUT/compile.jsonl"
F="--xla_gpu_enable_triton_gemm=false --xla_gpu_force_compilation_parallelism=16"
run() { echo "=== $1 :: $2 $3"; XLA_FLAGS="$2" TF_CPP_MIN_LOG_LEVEL=0 TF_CPP_VMODULE="gpu_compiler=1,nvptx_compiler=1,compile_module_to_llvm_ir=1,autotuner_util=1,gemm_algorithm_picker=1" timeout 220 $B $3 > $OUT/$1.log 2>&1; grep -E "compile:|step_s|mfu|peak|Error" $OUT/$1.log | head -8; }
run scan_min "$F" "--scan --remat minimal"
run unrolled "$F" ""
cd $OUT && tar czf logs.tgz *.log && rm *.log

# ---- compile_d
B="python3 bench/train_step.py --preset qwen3_vl_4b --seq 4096 --batch 1 --attention cudnn --steps 8 --json $OUT/compile.jsonl"
F="--xla_gpu_enable_triton_gemm=false --xla_gpu_force_compilation_parallelism=16"
run() { echo "=== $1 :: $2 $3"; XLA_FLAGS="$2" TF_CPP_MIN_LOG_LEVEL=0 TF_CPP_VMODULE="gpu_compiler=1" timeout 220 $B $3 > $OUT/$1.log 2>&1; grep -E "compile:|step_s|mfu|peak|Error" $OUT/$1.log | head -8; grep "RunHloPasses for jit_step\|RunBackend for jit_step" $OUT/$1.log | sed 's/(cum.*//;s/^.*\] //'; }
run at1 "$F --xla_gpu_autotune_level=1" ""
run at2 "$F --xla_gpu_autotune_level=2" ""
run at1_scan "$F --xla_gpu_autotune_level=1" "--scan --remat minimal"
cd $OUT && tar czf logs.tgz *.log && rm *.log

# ---- compile_e
B="python3 bench/train_step.py --preset qwen3_vl_4b --seq 4096 --batch 1 --attention cudnn --steps 4 --json $OUT/compile.jsonl"
F="--xla_gpu_enable_triton_gemm=false --xla_gpu_force_compilation_parallelism=16"
XLA_FLAGS="$F" TF_CPP_MIN_LOG_LEVEL=0 TF_CPP_VMODULE="gpu_compiler=1,hlo_pass_pipeline=1" timeout 220 $B > $OUT/passes.log 2>&1
grep -E "compile:|step_s" $OUT/passes.log
cd $OUT && gzip passes.log

# ---- cmd_f
timeout 150 python3 bench/checkpoint_save.py --gib 24 --json $OUT/save_probe.json  # then a script of the same steps
B="python3 bench/train_command.py --data REAL_SHARDS --preset qwen3_vl_4b --seq 4096 --batch 1 --accum 1 --steps 50 --log-every 10 --save-every 25 --loader-workers 8"
timeout 400 $B --peer ../shared/bench/hf_peer.py --out /tmp/cmdF --json $OUT/cmd.jsonl --set master_fp32=false --set remat=none --set attention=cudnn --set compile_cache=/tmp/xla_cold > $OUT/cmdF.log 2>&1
echo rc $?
cp /tmp/cmdF/hf_peer.json $OUT/ 2>/dev/null; cp /tmp/cmdF/run/metrics.jsonl $OUT/metrics.jsonl 2>/dev/null
grep -v "WARNING\|^I0000\|^W0000\|it/s\|step/s" $OUT/cmdF.log | tail -15; cat $OUT/cmd.jsonl | cut -c1-900

# ---- cmd_g
nvidia-smi -L > $OUT/gpus.txt
COMMON="--set data=synthetic --set seq_len=2048 --set batch_size=8 --set grad_accum=2 --set steps=5 --set log_every=1 --set save_every=1000 --set eval_batches=0 --set export_hf=false --set warmup_steps=1 --set attention=cudnn --set compile_cache="
timeout 100 python3 -m jax3dc.cli train --init small --output-dir /tmp/one $COMMON > $OUT/one.log 2>&1; echo rc $? >> $OUT/one.log
cp /tmp/one/metrics.jsonl $OUT/one_metrics.jsonl
for r in 0 1; do
  CUDA_VISIBLE_DEVICES=$((2*r)),$((2*r+1)) JAX_COORDINATOR_ADDRESS=localhost:12355 JAX_NUM_PROCESSES=2 JAX_PROCESS_ID=$r timeout 100 python3 -m jax3dc.cli train --init small --output-dir /tmp/two $COMMON > $OUT/two_$r.log 2>&1 &
done
wait
cp /tmp/two/metrics.jsonl $OUT/two_metrics.jsonl
for f in $OUT/one.log $OUT/two_0.log; do echo == $f; grep -v "WARNING\|^I0000\|^W0000\|warp\|step/s" $f | tail -3; done
python3 - <<'PY'
import json, os
out = os.environ["OUT"]
for name in ("one", "two"):
    rows = [json.loads(l) for l in open(f"{out}/{name}_metrics.jsonl")]
    print(name, [(r["step"], r["loss"], r["scored_tokens"]) for r in rows if "loss" in r])
PY

# ---- cmd_h
nvidia-smi -L > $OUT/gpus.txt
COMMON="--set data=REAL_SHARDS --set seq_len=8192 --set grad_accum=4 --set steps=7 --set log_every=2 --set save_every=1000 --set keep_last=1 --set eval_batches=0 --set export_hf=false --set loader_workers=4 --set warmup_steps=5 --set remat=full --set attention=cudnn --set compile_cache="
CUDA_VISIBLE_DEVICES=0 timeout 170 python3 -m jax3dc.cli train --init qwen3_vl_4b --output-dir /tmp/g1 $COMMON --set batch_size=4 > $OUT/g1.log 2>&1; echo rc $? >> $OUT/g1.log
cp /tmp/g1/metrics.jsonl $OUT/g1_metrics.jsonl
timeout 170 python3 -m jax3dc.cli train --init qwen3_vl_4b --output-dir /tmp/g4 $COMMON --set batch_size=16 > $OUT/g4.log 2>&1; echo rc $? >> $OUT/g4.log
cp /tmp/g4/metrics.jsonl $OUT/g4_metrics.jsonl
python3 - <<'PY'
import json, os
out = os.environ["OUT"]
for name in ("g1", "g4"):
    try:
        rows = [json.loads(l) for l in open(f"{out}/{name}_metrics.jsonl")]
    except OSError as e:
        print(name, e); continue
    print(name, [(r["step"], round(r.get("loss", 0), 4), r.get("tokens_per_s"), r.get("mfu"), r.get("compile_s")) for r in rows])
PY
tail -2 $OUT/g1.log $OUT/g4.log
