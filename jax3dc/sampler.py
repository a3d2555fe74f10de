"""Loading a checkpoint and generating structures (or, for the code task, part programs from
image I alone) in batches: the decode front-end of ``eval run``, ``predict`` and the demo.

Prompts are tokenised once up front (ids only; pixels are made per batch, so a large split does
not sit in memory as patches), left-padded to a multiple of ``bucket`` (few distinct shapes, few
recompiles) and run through a jitted prefill + the jitted decode loop of ``jax3dc.generate``. The
prefill passes ``vision_window`` = the largest image's patch count so each image attends only to
itself (full packed attention over a whole batch of images runs out of memory).

Decoding follows ``DecodeOptions`` (``jax3dc.decoding``, beside the commands' decoding flags):
under the grammar of the prompts' task (``jax3dc.constrained.task_constraint``) unless
``constrained`` is off, structure replies rewritten afterwards by ``jax3dc.reply_rewrite`` (pivots
back to absolute, scene grouping, grounding), and with
``candidates`` K > 1 each prompt's prompt pass is repeated into K rows: the first greedy, the
others sampled (temperature, top-p), all in one batched decode.

Writing predictions to a file and resuming a killed run is the evaluation's (``eval.generation``).
"""

from __future__ import annotations

import io
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Protocol, Sequence

import jax
import jax.numpy as jnp
import numpy as np
from PIL import Image

from jax3dc.constrained import task_constraint
from jax3dc.decoding import DecodeOptions
from jax3dc.errors import InputFileError
from jax3dc.generate import GenerationConfig, decode, left_pad, prefill, repeat_rows
from jax3dc.model.params import load_pretrained
from jax3dc.processing.chat import encode_chat
from jax3dc.processing.processor import ImageProcessorConfig, preprocess_images, smart_resize
from jax3dc.processing.tokenizer import load_tokenizer
from jax3dc.prompt import IMAGES_PER_TASK, chat_messages, code_messages, parameters_messages
from jax3dc.reply_rewrite import ReplyRewrite
from jax3dc.structure.box_frame import PivotFrame


class Example(Protocol):
    """What a prompt is made from: I and S as PNG bytes and the SPEC §3 prompt text (a dataset
    record, ``data_pipeline.record.Record``, is one)."""

    key: str
    image_png: bytes
    seg_png: bytes
    prompt: str


@dataclass(frozen=True)
class Sample:
    """One generated candidate."""

    text: str  # every generated token decoded (a tokenizer may spell out the stop token)
    new_tokens: int
    stopped: bool  # ended on a stop token (not cut at max_new_tokens)
    logprob: float
    reply: str = ""  # the tokens before the stop token: the model's answer as predict reads it

    def to_dict(self) -> dict[str, Any]:
        return {"text": self.text, "new_tokens": self.new_tokens, "stopped": self.stopped, "logprob": round(self.logprob, 4)}


@dataclass(frozen=True)
class Prompt:
    """One record's prompt ids and what is needed to make its pixels later."""

    key: str
    input_ids: np.ndarray
    record: Example
    task: str = "structure"  # or "code": image I alone -> part program; "parameters": I alone -> factory parameters


@dataclass(frozen=True)
class Sampler:
    """A loaded checkpoint (model, its config, tokenizer and image processor settings, and how it
    writes pivots) and the one way to decode with it: ``generate_batch`` serves ``eval run``
    (batches of records), ``predict`` and the demo (one in-memory image at a time), greedy or with
    sampled candidates, under a task's grammar or not. Structure texts come back with SPEC §2
    absolute pivots whatever frame the model writes them in."""

    model: Any
    config: Any
    tokenizer: Any
    processor: Any
    pivot_frame: PivotFrame = PivotFrame()

    @classmethod
    def load(cls, checkpoint: str | Path, dtype: str = "bfloat16") -> "Sampler":
        checkpoint = Path(checkpoint)
        if not (checkpoint / "config.json").is_file():
            raise InputFileError(checkpoint, "not a checkpoint folder (no config.json)")
        model, config = load_pretrained(checkpoint, dtype=getattr(jnp, dtype))
        # An export with weights only (train's export_hf) falls back to the packaged Qwen3 tokenizer
        # and the released Qwen3-VL image settings, said on stderr so nobody mistakes it silently.
        if (checkpoint / "tokenizer.json").is_file():
            tokenizer = load_tokenizer(checkpoint)
        else:
            print(f"note: no tokenizer.json in {checkpoint}; using the packaged Qwen3 tokenizer", file=sys.stderr)
            tokenizer = load_tokenizer()
        if (checkpoint / "preprocessor_config.json").is_file():
            processor = ImageProcessorConfig.from_pretrained(checkpoint)
        else:
            print(f"note: no preprocessor_config.json in {checkpoint}; using Qwen3-VL's image settings", file=sys.stderr)
            processor = ImageProcessorConfig.qwen3_vl()
        return cls(model, config, tokenizer, processor, PivotFrame.load(checkpoint))

    def images(self, record: Example, task: str = "structure") -> list:
        """I and S for the structure task, I alone for the code task."""
        try:
            return [Image.open(io.BytesIO(blob)) for blob in (record.image_png, record.seg_png)[:IMAGES_PER_TASK[task]]]
        except OSError as e:
            raise InputFileError(record.key, f"record image is not a readable PNG: {e}") from None

    def grids(self, record: Example, task: str = "structure") -> np.ndarray:
        """(t, h, w) patch grid of the task's images from the PNG sizes alone (no pixel decoding)."""
        p = self.processor
        rows = []
        for image in self.images(record, task):
            height, width = smart_resize(image.height, image.width, p.factor, p.min_pixels, p.max_pixels)
            rows.append((1, height // p.patch_size, width // p.patch_size))
        return np.asarray(rows, dtype=np.int64)

    def prompt(self, record: Example, task: str = "structure") -> Prompt:
        messages = (chat_messages(record.prompt) if task == "structure" else
                    parameters_messages() if task == "parameters" else code_messages())
        chat = encode_chat(self.tokenizer, messages, self.grids(record, task),
                           self.config.vision.spatial_merge_size, add_generation_prompt=True)
        return Prompt(record.key, chat.input_ids, record, task)

    def generate_batch(self, prompts: Sequence[Prompt], batch_size: int, max_new_tokens: int, bucket: int,
                       options: DecodeOptions = DecodeOptions()) -> list[list[Sample]]:
        """``options.candidates`` samples per prompt (the first greedy); the batch is topped up to
        ``batch_size`` prompts with copies of its last one so every full batch has the same shape."""
        rows = list(prompts) + [prompts[-1]] * (batch_size - len(prompts))
        k = options.candidates
        special = self.tokenizer.special
        ids, mask = left_pad([p.input_ids for p in rows], special.endoftext, multiple=bucket)
        processed = [preprocess_images(self.images(p.record, p.task), self.processor) for p in rows]
        pixels = np.concatenate([x.pixel_values for x in processed])
        grid = np.concatenate([x.image_grid_thw for x in processed])
        window = int(np.prod(grid, axis=1).max())
        prefilled = prefill(self.model, ids, mask, pixels, grid, max_new_tokens, vision_window=window)
        if k > 1:
            prefilled = repeat_rows(prefilled, k)
        config = GenerationConfig(max_new_tokens=max_new_tokens, stop_ids=special.stop_ids, pad_id=special.endoftext,
                                  temperature=options.temperature if k > 1 else 0.0, top_p=options.top_p if k > 1 else 1.0)
        # Room per row: the decode's max_new_tokens, or less where the model's context ends first.
        context = self.config.text.max_position_embeddings
        room = [min(max_new_tokens, context - len(p.input_ids)) for p in rows for _ in range(k)]
        constraint = None
        if options.constrained:
            tasks = {p.task for p in rows}
            if len(tasks) > 1:
                raise ValueError(f"one batch mixes tasks {sorted(tasks)}: each task has its own grammar")
            constraint = task_constraint(rows[0].task, self.tokenizer, self.config.text.vocab_size,
                                         [p.record.prompt for p in rows for _ in range(k)],
                                         [p.key for p in rows for _ in range(k)], room, options.schemas)
        greedy = (np.arange(len(rows) * k) % k == 0) if k > 1 else None
        out = decode(self.model, prefilled, config, jax.random.key(options.seed), greedy, constraint)
        tokens, lengths, logprobs = np.asarray(out.tokens), np.asarray(out.lengths), np.asarray(out.logprobs)

        rewrite = ReplyRewrite(self.pivot_frame, options.scene_grouping, options.grounding)

        def sample(i: int, boxes: dict | None) -> Sample:
            n = int(lengths[i])
            stopped = bool(n) and int(tokens[i, n - 1]) in special.stop_ids
            text, reply = self.tokenizer.decode(tokens[i, :n].tolist()), self.tokenizer.decode(tokens[i, :n - stopped].tolist())
            if boxes is not None:
                text, reply = rewrite(text, boxes), rewrite(reply, boxes)
            return Sample(text, n, stopped, float(logprobs[i]), reply)

        return [[sample(r * k + c, boxes) for c in range(k)]
                for r, boxes in ((r, rewrite.boxes(rows[r].record.prompt) if rows[r].task == "structure" else None)
                                 for r in range(len(prompts)))]
