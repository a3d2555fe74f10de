"""The release recipe's training mix: every source gets its share, and the shares sum to one."""

import pytest

from bench.release_model import training_mix


def test_procedural_only():
    assert training_mix("B", "", 0.3, 0.0) == (["B"], ["structure"], [1.0])


def test_one_real_import_takes_its_share():
    data, tasks, weights = training_mix("B", "R", 0.3, 0.0)
    assert data == ["B", "R"] and tasks == ["structure", "structure"]
    assert weights == pytest.approx([0.7, 0.3])


def test_several_real_imports_split_the_real_share():
    data, tasks, weights = training_mix("B", "R1,R2,", 0.3, 0.1)
    assert data == ["B", "R1", "R2", "B"]
    assert tasks == ["structure", "structure", "structure", "code"]
    assert weights == pytest.approx([0.6, 0.15, 0.15, 0.1])
    assert sum(weights) == pytest.approx(1.0)
