"""The fixtures of the serve tests (serve_cases.py): the cabinet predicted once per session, and
a fresh server per test whose --out holds it as the done job "cabinet"."""

from __future__ import annotations

import pytest

from tests.serve.serve_cases import predicted_inputs, served_app


@pytest.fixture(scope="session")
def inputs(tmp_path_factory):
    """(the stand-in config, the cabinet's image, an --out with it predicted as "cabinet")."""
    return predicted_inputs(tmp_path_factory.mktemp("serve_inputs"))


@pytest.fixture
def served(inputs, tmp_path):
    """A running server (its worker stopped after the test)."""
    server = served_app(inputs, tmp_path)
    with server.client:
        yield server
    server.board.stop()
