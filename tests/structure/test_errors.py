"""Typed errors survive a trip between processes (jax3dc.errors): a worker's error reaches the parent."""

import pickle

import pytest

from jax3dc.errors import InputFileError, ProgramError, SetupError, StructureError


@pytest.mark.parametrize("error", [InputFileError("parts/3.obj", "the mesh has no triangles"),
                                   StructureError("json", "line 1 column 2", "invalid JSON"),
                                   ProgramError(3, "unknown name 'boxx'"), ProgramError(None, "empty program"),
                                   SetupError("cannot render")])
def test_error_pickles_with_its_fields(error):
    back = pickle.loads(pickle.dumps(error))
    assert type(back) is type(error) and str(back) == str(error) and vars(back) == vars(error)
