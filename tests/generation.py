"""Generation straight from token ids (prompt rows already tokenised and left-padded): the model
tests' way into ``jax3dc.generate``'s prefill and decode, without the sampler's checkpoint folder,
processor and chat template (every product decode goes through ``jax3dc.sampler.Sampler``)."""

from __future__ import annotations

import jax
import numpy as np

from jax3dc.constrained import Constraint
from jax3dc.generate import GenerationConfig, Generated, decode, prefill, prefill_in_chunks


def generate(model, input_ids, attention_mask=None, pixel_values=None, image_grid_thw=None,
             config: GenerationConfig = GenerationConfig(), key: jax.Array | None = None,
             prefill_rows: int | None = None, greedy=None, constraint: Constraint | None = None) -> Generated:
    """Generate up to ``config.max_new_tokens`` tokens for each (left-padded) prompt row.

    ``pixel_values`` / ``image_grid_thw`` are the image processor's output for all images of
    all rows, in row order. ``prefill_rows`` runs the prompt pass that many rows at a time.
    """
    if prefill_rows is not None and prefill_rows < np.shape(input_ids)[0]:
        prefilled = prefill_in_chunks(model, input_ids, attention_mask, pixel_values, image_grid_thw,
                                      config.max_new_tokens, prefill_rows)
    else:
        prefilled = prefill(model, input_ids, attention_mask, pixel_values, image_grid_thw, config.max_new_tokens)
    return decode(model, prefilled, config, key, greedy, constraint)
