"""The release recipe's training mix: every source gets its share, and the shares sum to one."""

import pytest

from recipes.release_model import training_mix


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


def test_mixed_in_folders_take_their_own_shares():
    data, tasks, weights = training_mix("B", "R", 0.3, 0.0, [("C", 0.15)])
    assert data == ["B", "R", "C"] and tasks == ["structure"] * 3
    assert weights == pytest.approx([0.55, 0.3, 0.15])


def test_shares_that_leave_the_build_nothing_are_refused():
    with pytest.raises(SystemExit, match="leave the build none"):
        training_mix("B", "R", 0.6, 0.0, [("C", 0.4)])


@pytest.mark.parametrize("text", ["C", "C=0", "C=1.5", "=0.2", "C=x"])
def test_mix_entry_names_a_bad_value(text):
    import argparse

    from recipes.release_model import mix_entry
    with pytest.raises(argparse.ArgumentTypeError, match="DIR=SHARE"):
        mix_entry(text)
