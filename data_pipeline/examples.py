"""A dataset record as the model trains on it: chat tokens, loss labels and image patches.

Two tasks read the same records (SPEC §4, §6):

* ``structure`` (stage 2): images I and S, the record's prompt -> the target JSON;
* ``code`` (stage-1 code backend): image I and CODE_PROMPT -> the record's part program;
* ``parameters`` (stage-1 parameter backend): image I and PARAMETERS_PROMPT -> the record's
  factory parameters (jax3dc.parameters), which the factory runs into the same parts.

The chat is built exactly as generation builds it (jax3dc.prompt + jax3dc.processing.chat), so a
model sees at inference the very tokens it was trained on, up to the assistant answer.
"""

from __future__ import annotations

import io
from dataclasses import dataclass

import numpy as np
from PIL import Image

from data_pipeline.importers.material_guess import placeholder_spans
from data_pipeline.packing import Example
from data_pipeline.record import Record
from jax3dc.errors import Jax3dcError
from jax3dc.processing.chat import encode_chat
from jax3dc.processing.processor import ImageProcessorConfig, preprocess_images
from jax3dc.processing.tokenizer import Tokenizer
from jax3dc.errors import StructureError
from jax3dc.prompt import IMAGES_PER_TASK, chat_messages, code_messages, legend_boxes, parameters_messages
from jax3dc.structure.box_frame import PivotFrame, target_in_frame

TASKS = ("structure", "code", "parameters")


class UnusableRecord(Jax3dcError):
    """A record that cannot become a training example (bad PNG, no program for the code task)."""

    reason = "corrupt"


class MissingProgram(UnusableRecord):
    """A record without a part program, asked for by the code task."""

    reason = "no_program"


class MissingParameters(UnusableRecord):
    """A record without factory parameters (an imported, augmented or scene record), asked for by
    the parameters task."""

    reason = "no_parameters"


@dataclass(frozen=True)
class ExampleEncoder:
    """Turns records into Examples; picklable, so grain workers each hold a copy."""

    tokenizer: Tokenizer
    processor: ImageProcessorConfig
    merge: int
    task: str = "structure"
    image_size: int | None = None  # resize I and S to this square side first (S nearest-neighbour)
    pivot_frame: PivotFrame = PivotFrame()  # how the structure target writes joint pivots
    # Off: the material text an importer writes where its source names no material takes no loss
    # (material_guess.placeholder_spans): only imported objects have it, so learning it would teach
    # the model which domain an object comes from, not what it is made of.
    score_placeholder_materials: bool = False

    @property
    def images_per_example(self) -> int:
        return IMAGES_PER_TASK[self.task]

    def images(self, record: Record) -> list[Image.Image]:
        blobs = (record.image_png, record.seg_png)[: self.images_per_example]
        out = []
        for name, blob in zip(("image", "segmentation"), blobs):
            try:
                image = Image.open(io.BytesIO(blob))
                image.load()
            except (OSError, ValueError) as e:
                raise UnusableRecord(f"record {record.key!r}: {name} PNG is not readable: {e}") from None
            if self.image_size and image.size != (self.image_size, self.image_size):
                resample = Image.Resampling.NEAREST if name == "segmentation" else Image.Resampling.BICUBIC
                image = image.convert("RGB").resize((self.image_size, self.image_size), resample)
            out.append(image)
        return out

    def structure_target(self, record: Record) -> str:
        """The structure task's answer: the record's target with pivots in the run's frame."""
        try:
            return target_in_frame(record.target, legend_boxes(record.prompt), self.pivot_frame)
        except StructureError as e:
            raise UnusableRecord(f"record {record.key!r}: target is not a valid structure: {e}") from None

    def messages(self, record: Record) -> list[dict]:
        if self.task == "structure":
            return chat_messages(record.prompt, self.structure_target(record))
        if self.task == "parameters":
            if not record.parameters:
                raise MissingParameters(f"record {record.key!r} has no factory parameters (parameters task)")
            return parameters_messages(record.parameters)
        if not record.program:
            raise MissingProgram(f"record {record.key!r} has no part program (code task)")
        return code_messages(record.program)

    def encode(self, record: Record) -> Example:
        messages = self.messages(record)
        unscored: list[tuple[int, int]] = []
        if self.task == "structure" and not self.score_placeholder_materials:
            unscored = placeholder_spans(messages[-1]["content"][0]["text"])  # the answer: the target
        processed = preprocess_images(self.images(record), self.processor)
        chat = encode_chat(self.tokenizer, messages, processed.image_grid_thw, self.merge, unscored=unscored)
        return Example(record.key, chat.input_ids, chat.labels, processed.pixel_values,
                       np.asarray(processed.image_grid_thw, np.int64))
