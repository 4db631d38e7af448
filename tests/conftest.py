"""Fixtures shared by several test modules.

A model folder is meshed once per session (`*_source`, never written to) and each module gets its
own copy under the plain name (`cyl8`, `section`): some tests write into the model folder (a
stored response model in `response/`, run folders), and a stored response model changes how
later `indent` runs behave, so no module may see another module's files.
"""
import shutil

import pytest

import pipeline
from fem.thesis.findings import LEVELS, MeshLevel, Workshop

TEST_LEVEL = MeshLevel("tests: 0.25 mm 2D, 1 mm 3D", 0.25, 1.0)
"""The meshes the thesis-claim tests pin their numbers on: the coarsest 2D level and the 1 mm 3D presets."""


@pytest.fixture(scope="session")
def shop(tmp_path_factory):
    """One Workshop for every thesis-claim test (TEST_LEVEL): each 2D model and 3D preset is meshed once."""
    return Workshop(tmp_path_factory.mktemp("thesis_models"), quick=True, level=TEST_LEVEL)


def _mesh(folder, *args):
    assert pipeline.main(["mesh", *args, "--out", str(folder), "--quiet"]) == 0
    return folder


def _copy(source, tmp_path_factory):
    """A copy of a model folder, under the same name, in a new temporary folder."""
    folder = tmp_path_factory.mktemp(f"{source.name}_copy") / source.name
    shutil.copytree(source, folder)
    return folder


@pytest.fixture(scope="session")
def fine_shop(tmp_path_factory):
    """A Workshop on the next mesh level (0.125 mm 2D) for the claims the test level cannot resolve
    (two bars 0.25 mm apart on 0.25 mm elements)."""
    return Workshop(tmp_path_factory.mktemp("thesis_models_fine"), quick=False, level=LEVELS[1])


@pytest.fixture(scope="session")
def cyl8_source(tmp_path_factory):
    """The 2D cylinder8 model with bone (`mesh --preset cylinder8 --bone`), meshed once; use `cyl8`."""
    return _mesh(tmp_path_factory.mktemp("models") / "cyl8", "--preset", "cylinder8", "--bone")


@pytest.fixture(scope="module")
def cyl8(cyl8_source, tmp_path_factory):
    """This module's own copy of the 2D cylinder8 model with bone."""
    return _copy(cyl8_source, tmp_path_factory)


@pytest.fixture(scope="session")
def section_source(tmp_path_factory):
    """Coarse five-layer 2D cross-section of the monkey model (`mesh --preset monkey --section-z 5
    --size 0.25`, ~4k DOFs), meshed once; use `section`."""
    return _mesh(tmp_path_factory.mktemp("models") / "msec", "--preset", "monkey", "--section-z", "5",
                 "--size", "0.25")


@pytest.fixture(scope="module")
def section(section_source, tmp_path_factory):
    """This module's own copy of the coarse monkey section."""
    return _copy(section_source, tmp_path_factory)
