#!/usr/bin/env bash
# Issue 10 / issue 6 scaling figures through the trainer (bench/train_step.py) on one host:
# the 4B config, random weights, frozen vision tower, 8192 tokens per row, one row per GPU,
# full remat, cuDNN attention. Layouts that use disjoint GPUs run at the same time; on four GPUs:
# FSDP 4, data 2 x FSDP 2 and FSDP 2 x tensor 2.
#   bash bench/train_layouts.sh OUT.jsonl [GPUS]     (GPUS: 2, 4 or 8)
set -uo pipefail
out=${1:?usage: train_layouts.sh OUT.jsonl [GPUS]}; gpus=${2:-$(nvidia-smi -L | wc -l)}
step() {  # visible devices, mesh data,fsdp,tensor
  local n; n=$(awk -F, '{print NF}' <<<"$1")
  CUDA_VISIBLE_DEVICES=$1 python3 bench/train_step.py --preset qwen3_vl_4b --seq 8192 --batch "$n" \
    --remat full --attention cudnn --steps 6 --mesh "$2" --json "$out" 2>&1 | grep -E "step_s|mfu|peak|Error" | sed "s/^/[$1 $2] /"
}
step 0 1,1,1 & step 1,2 1,2,1 & wait
if [ "$gpus" -ge 4 ]; then step 0,1,2,3 1,4,1; step 0,1,2,3 2,2,1; step 0,1,2,3 1,2,2; fi
if [ "$gpus" -ge 8 ]; then step 0,1,2,3,4,5,6,7 1,8,1; step 0,1,2,3,4,5,6,7 1,4,2; fi
python3 - "$out" <<'PY'
import json, sys
rows = [json.loads(l) for l in open(sys.argv[1])]
one = next((r for r in rows if r["devices"] == 1), None)
for r in rows:
    eff = r["tokens_per_s_per_device"] / one["tokens_per_s_per_device"] if one else float("nan")
    print(f"{r['device']} x{r['devices']} mesh {r['mesh']}: {r['tokens_per_s']:,.0f} tok/s, {r['tokens_per_s_per_device']:,.0f}/GPU, "
          f"MFU {100 * r['mfu_vs_989']:.1f}%, peak {r['peak_mem_gib']:.1f} GiB/GPU, step {r['step_s']:.2f} s, "
          f"scaling efficiency {100 * eff:.0f}%, setup+compile {r['setup_and_compile_s']:.0f} s")
PY
