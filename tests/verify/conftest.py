"""Small data builds that the verified-decoding tests read, made once per session through the
build's own entry point (``run_build``, what ``jax3dc data build`` / ``data import`` run)."""

from pathlib import Path

import pytest

from data_pipeline.build import BuildConfig, SourceSpec, factory_sources, import_sources, run_build
from data_pipeline.record import Record
from data_pipeline.shards import read_dataset
from jax3dc.factories import object_id
from tests.verify.verified_cases import IMPORTED
from tests.shared_fixtures import partnet_object


def _records(directory: Path) -> dict[str, Record]:
    return {r.key: r for r in read_dataset(directory)}


@pytest.fixture(scope="session")
def posed_records(tmp_path_factory) -> dict[str, Record]:
    """Factory objects in three views (rest, then a joint moved) with split / merge variants."""
    out = tmp_path_factory.mktemp("posed")
    run_build(out, factory_sources(4, 3), BuildConfig(views=3, seed=3, size=32, objects_per_shard=8, augment=True),
              workers=1, progress=False)
    return _records(out)


@pytest.fixture(scope="session")
def imported_records(tmp_path_factory) -> dict[str, Record]:
    """PartNet-Mobility fixtures in two views with split variants."""
    out = tmp_path_factory.mktemp("imported")
    run_build(out, import_sources([partnet_object(name) for name in IMPORTED]),
              BuildConfig(views=2, seed=0, size=32, objects_per_shard=8, augment=True, split="test"),
              workers=1, progress=False)
    return _records(out)


@pytest.fixture(scope="session")
def checked_records(tmp_path_factory) -> dict[str, Record]:
    """Rest views of objects whose verdicts are quick (about 0.3-0.7 s on 2 cores): a storage box
    (one lid hinge) and a microwave (door hinge and turntable)."""
    out = tmp_path_factory.mktemp("checked")
    specs = [SourceSpec("factory", object_id(category, 1), category=category, seed=1)
             for category in ("storage_box", "microwave")]
    run_build(out, specs, BuildConfig(views=1, seed=0, size=32, objects_per_shard=8, split="test"),
              workers=1, progress=False)
    return _records(out)
