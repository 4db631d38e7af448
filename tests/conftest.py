"""Fixtures shared by several test modules."""
import pytest

from fem.thesis.findings import Workshop


@pytest.fixture(scope="session")
def shop(tmp_path_factory):
    """One quick Workshop for every thesis-claim test: each 2D model and 3D preset is meshed once."""
    return Workshop(tmp_path_factory.mktemp("thesis_models"), quick=True)
