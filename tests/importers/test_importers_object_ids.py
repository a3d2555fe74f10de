"""Every imported object gets a unique, readable id at import time (issue 46): two models of the
same file name in different folders build into one dataset whose record keys are all distinct."""

from __future__ import annotations

from pathlib import Path

import pytest

from data_pipeline.importers.object_ids import object_ids
from data_pipeline.shards import read_dataset
from jax3dc.cli import main
from jax3dc.errors import InputFileError

MICROWAVE = """<robot name="microwave">
  <link name="body"><visual><geometry><box size="0.6 0.4 0.4"/></geometry></visual></link>
  <link name="door"><visual><origin xyz="0 -0.01 0"/><geometry><box size="0.6 0.02 0.4"/></geometry></visual></link>
  <joint name="hinge" type="revolute"><origin xyz="-0.3 -0.21 0"/><axis xyz="0 0 1"/>
    <parent link="body"/><child link="door"/><limit lower="-1.5" upper="0"/></joint>
</robot>
"""


def _model(path: Path) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(MICROWAVE)
    return path


def test_unique_names_are_kept_and_shared_names_take_the_fewest_telling_folders(tmp_path):
    paths = [tmp_path / "x" / "a" / "microwave.xml", tmp_path / "y" / "a" / "microwave.xml",
             tmp_path / "z" / "b" / "microwave.xml", tmp_path / "door_8877", tmp_path / "k" / "c" / "lamp.xml",
             tmp_path / "l" / "d" / "lamp.xml"]
    assert object_ids(paths) == ["x__a__microwave.xml", "y__a__microwave.xml", "z__b__microwave.xml", "door_8877",
                                 "c__lamp.xml", "d__lamp.xml"]
    assert object_ids(paths) == object_ids(list(paths))  # deterministic
    assert object_ids([tmp_path / "sub" / "m.xml", tmp_path / "m.xml"]) == ["sub__m.xml", f"{tmp_path.name}__m.xml"]


def test_a_source_given_twice_or_an_unresolvable_clash_is_refused_naming_both(tmp_path):
    with pytest.raises(InputFileError, match="given twice") as caught:
        object_ids([tmp_path / "a" / "m.xml", tmp_path / "a" / ".." / "a" / "m.xml"])
    assert "a/m.xml" in str(caught.value) and "a/../a/m.xml" in str(caught.value)
    with pytest.raises(InputFileError, match="'a__m.xml' is also the id of") as caught:
        object_ids([tmp_path / "a" / "m.xml", tmp_path / "b" / "m.xml", tmp_path / "c" / "a__m.xml"])
    assert str(tmp_path / "a" / "m.xml") in str(caught.value) and str(tmp_path / "c" / "a__m.xml") in str(caught.value)


def test_same_file_name_in_two_folders_imports_into_distinct_keys(tmp_path, capsys):
    first, second = _model(tmp_path / "a" / "microwave.xml"), _model(tmp_path / "b" / "microwave.xml")
    out = tmp_path / "out"
    common = ["--out", str(out), "--views", "2", "--size", "32", "--split", "test", "--quiet"]
    assert main(["data", "import", str(first), str(second), *common]) == 0
    records = list(read_dataset(out))
    assert len(records) == 4 and len({r.key for r in records}) == 4
    assert {r.meta["object_id"] for r in records} == {"a__microwave.xml", "b__microwave.xml"}

    # the build cannot be appended to: another import into the same --out is refused, not merged
    third = _model(tmp_path / "c" / "microwave.xml")
    assert main(["data", "import", str(third), *common]) != 0
    assert "holds a build with other settings or sources" in capsys.readouterr().err
    assert len(list(read_dataset(out))) == 4
