"""Where a run's numbers go: a JSONL file (always), TensorBoard (if tensorboardX is installed)
and a tqdm bar on the console; plus the FLOP count behind tokens/s -> MFU.

MFU convention (the same as the HF peer baseline in docs/BENCHMARKS.md, so figures compare):

    FLOPs per optimiser step = tokens * (6 * N_dense + 6 * layers * S * heads * head_dim)
                               + images * 2 * N_vision * patches_per_image

    N_dense   decoder matmul parameters per token: every layer's q, k, v, o and SwiGLU
              projections plus the LM head (vocab * hidden, whether tied or not); the input
              embedding is a lookup and is not counted. 6 = forward 2 + backward 4.
    attention causal attention scores and values, forward + backward: 6 * S * heads * head_dim
              per token and layer at sequence length S (half of the 12 for full attention).
    vision    the frozen tower runs forward only: 2 FLOPs per parameter per patch.

MFU = FLOPs / step time / peak, with the peak dense bf16 FLOP/s of the device from PEAK_FLOPS
(unknown devices, e.g. CPU, get no MFU).
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass
from typing import Any, Mapping, Sequence

from tqdm import tqdm

PEAK_FLOPS = {  # dense bf16 FLOP/s, from the vendor data sheets (SXM parts)
    "H100": 989e12,
    "H200": 989e12,
    "A100": 312e12,
}


METRICS_FILE = "metrics.jsonl"

def peak_flops(device_kind: str) -> float | None:
    for name, flops in PEAK_FLOPS.items():
        if name.lower() in device_kind.lower():
            return flops
    return None


def peak_memory_gib(devices: Sequence[Any]) -> float | None:
    """The most device memory any of `devices` has held since the process started, in GiB; None
    where the backend keeps no count (CPU). Logged with each step so a run shows whether its
    settings fit a smaller card (issue 51: the 4B at fp32 quality on 80 GB)."""
    peaks = [(d.memory_stats() or {}).get("peak_bytes_in_use") for d in devices]
    peaks = [p for p in peaks if p is not None]
    return max(peaks) / 2**30 if peaks else None


@dataclass(frozen=True)
class FlopsModel:
    """The numbers of the model that the FLOP count needs."""

    layers: int
    hidden: int
    heads: int
    kv_heads: int
    head_dim: int
    intermediate: int
    vocab: int
    vision_params: int  # whole frozen vision tower incl. mergers
    patches_per_image: int
    # False with LoRA: frozen decoder weights get no gradient, so each costs 4 FLOPs per token
    # (forward, input gradient) instead of 6; the adapters' own are negligible at low rank.
    weight_grads: bool = True

    @classmethod
    def from_model_config(cls, cfg: Any, vision_params: int, patches_per_image: int,
                          weight_grads: bool = True) -> "FlopsModel":
        t = cfg.text
        return cls(layers=t.num_hidden_layers, hidden=t.hidden_size, heads=t.num_attention_heads,
                   kv_heads=t.num_key_value_heads, head_dim=t.head_dim,
                   intermediate=t.intermediate_size, vocab=t.vocab_size,
                   vision_params=vision_params, patches_per_image=patches_per_image,
                   weight_grads=weight_grads)

    @property
    def dense_params(self) -> int:
        h, q, kv = self.hidden, self.heads * self.head_dim, self.kv_heads * self.head_dim
        per_layer = h * q + 2 * h * kv + q * h + 3 * h * self.intermediate
        return self.layers * per_layer + self.vocab * h

    def step_flops(self, rows: int, seq_len: int) -> float:
        """FLOPs of one optimiser step over `rows` sequences of `seq_len` with one image each."""
        per_weight = 6 if self.weight_grads else 4
        per_token = per_weight * self.dense_params + 6 * self.layers * seq_len * self.heads * self.head_dim
        vision = 2 * self.vision_params * self.patches_per_image if self.patches_per_image else 0
        return rows * (seq_len * per_token + vision)


class MetricsLog:
    """Writes one JSON object per logged step; only the first process writes anything."""

    def __init__(self, directory: str, *, total_steps: int, first_step: int = 0, enabled: bool = True,
                 progress: bool = True):
        self.enabled = enabled
        self.path = os.path.join(directory, METRICS_FILE)
        self._file = None
        self._tb = None
        self._bar = None
        if not enabled:
            return
        os.makedirs(directory, exist_ok=True)
        self._file = open(self.path, "a", buffering=1)
        try:
            from tensorboardX import SummaryWriter  # lazy: an optional package
        except ImportError:  # TensorBoard is optional: the JSONL file holds everything
            SummaryWriter = None
        if SummaryWriter is not None:
            self._tb = SummaryWriter(os.path.join(directory, "tensorboard"))
        if progress:
            self._bar = tqdm(total=total_steps, initial=first_step, desc="train", unit="step",
                             dynamic_ncols=True)

    def write(self, step: int, values: Mapping[str, float], kind: str = "train") -> None:
        if not self.enabled:
            return
        record = {"step": int(step), "kind": kind, **{k: float(v) for k, v in values.items()}}
        self._file.write(json.dumps(record) + "\n")
        if self._tb is not None:
            for k, v in values.items():
                self._tb.add_scalar(f"{kind}/{k}", float(v), int(step))
        if self._bar is not None:
            shown = {k: f"{v:.4g}" for k, v in values.items() if k in ("loss", "accuracy", "lr", "mfu")}
            self._bar.set_postfix(shown if kind == "train" else {f"{kind}_{k}": f"{v:.4g}"
                                                                  for k, v in values.items()})

    def advance(self, steps: int = 1) -> None:
        if self._bar is not None:
            self._bar.update(steps)

    def message(self, text: str) -> None:
        if not self.enabled:
            return
        if self._bar is not None:
            self._bar.write(text)
        else:
            print(text, flush=True)

    def close(self) -> None:
        if self._bar is not None:
            self._bar.close()
        if self._tb is not None:
            self._tb.close()
        if self._file is not None:
            self._file.close()


def read_metrics(path: str, kind: str = "train") -> list[dict]:
    """The records of one kind, in file order (a resumed run appends after its predecessor)."""
    with open(path) as f:
        return [r for r in map(json.loads, f) if r.get("kind") == kind]


def plot_losses(run_dir: str) -> str:
    """loss.png in the run folder: training loss and accuracy per step, validation loss on top."""
    import matplotlib  # lazy: matplotlib (0.31 s with pyplot), once at the end of a run

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt  # lazy: after the Agg backend is chosen

    path = os.path.join(run_dir, METRICS_FILE)
    train, val = read_metrics(path), read_metrics(path, "val")
    fig, (ax, acc) = plt.subplots(1, 2, figsize=(10, 3.6))
    ax.plot([r["step"] for r in train], [r["loss"] for r in train], label="train")
    if val:
        ax.plot([r["step"] for r in val], [r["loss"] for r in val], "o-", label="validation")
    ax.set(xlabel="step", ylabel="token NLL", yscale="log", title="loss")
    ax.legend()
    if train and "accuracy" in train[0]:
        acc.plot([r["step"] for r in train], [r["accuracy"] for r in train])
    acc.set(xlabel="step", ylabel="next-token accuracy", title="accuracy", ylim=(0, 1))
    fig.tight_layout()
    out = os.path.join(run_dir, "loss.png")
    fig.savefig(out, dpi=120)
    plt.close(fig)
    return out
