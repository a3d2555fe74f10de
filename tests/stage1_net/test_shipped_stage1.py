"""The shipped stage-1 network (jax3dc/release/stage1) loads, stays small and reads an image into a
parameter text the factory runs."""

from __future__ import annotations

import numpy as np

from jax3dc.factories.registry import SCHEMAS, run_parameters
from jax3dc.parameters import parse_parameters
from jax3dc.release import STAGE1_DIR
from jax3dc.stage1_net import MARKER, load_network, load_reader


def test_the_shipped_folder_is_small_and_knows_every_category():
    assert (STAGE1_DIR / MARKER).is_file() and (STAGE1_DIR / "MODEL_CARD.md").is_file()
    assert (STAGE1_DIR / "model.safetensors").stat().st_size < 10 * 2**20  # the 24 MiB budget is shared with stage 2
    shipped = load_network(STAGE1_DIR).schemas
    # the schemas it was trained on have not moved on; factories added since are simply unknown to it
    assert shipped and {category: SCHEMAS[category] for category in shipped} == shipped


def test_the_shipped_reader_writes_a_text_that_runs():
    image = np.full((120, 160, 3), 90, np.uint8)
    image[30:100, 60:100] = (150, 100, 60)  # a brown box on grey
    params = parse_parameters(load_reader(STAGE1_DIR)(image), SCHEMAS)
    assert run_parameters(params).parts
