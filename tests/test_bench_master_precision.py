"""bench.master_precision's verdict: each setting's last-step loss against fp32 master's, and the
mean of its last ten logged losses."""

import pytest

from bench.master_precision import REFERENCE, compare


def test_last_step_ratio_and_tail_mean():
    curves = {REFERENCE: {s: 2.0 for s in range(1, 41)},
              "bf16_master": {**{s: 6.0 for s in range(1, 40)}, 40: 6.3}}
    table = compare(curves)
    assert table[REFERENCE]["ratio_to_fp32"] == 1.0 and table[REFERENCE]["last_step"] == 40
    assert table["bf16_master"]["last_loss"] == 6.3
    assert table["bf16_master"]["ratio_to_fp32"] == pytest.approx(3.15)
    assert table["bf16_master"]["tail_mean_loss"] == pytest.approx(6.03)
