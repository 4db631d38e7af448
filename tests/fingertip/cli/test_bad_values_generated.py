"""Generated bad values (hypothesis) for the value-list options (--depth, --sweep,
--receptor-depths, --max-depth, --force) and the path options (--out, the model folder,
--scene) of `indent`: every one ends with exit code 2 and one `error:` line, no traceback and
nothing written, before the model is factorised (the factorisation raises `Started`, which
fails the test: none of these values may get that far)."""
from __future__ import annotations

import os

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from tests.helpers import cli, snapshot

SETTINGS = settings(max_examples=40, deadline=None, derandomize=True, database=None,
                    suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture])
TISSUE_MM = 3.0
"""The tissue over the bone of the 2D cylinder8 model with bone (its radius 4 mm, the bone's 1 mm)."""


class Started(BaseException):
    """Raised where the model would be factorised: a bad value got past every check."""


def _started(*args, **kwargs):
    raise Started


@pytest.fixture(scope="module")
def work(cyl8, tmp_path_factory):
    """cwd: a work folder with the model, a plain file, a folder of someone's files, a folder
    without a mesh; factorising raises Started."""
    base = tmp_path_factory.mktemp("bad_values")
    cwd = os.getcwd()
    os.chdir(base)
    (base / "a_file").write_text("x\n")
    (base / "mine").mkdir()
    (base / "mine" / "notes.txt").write_text("keep me\n")
    (base / "empty_dir").mkdir()
    patches = pytest.MonkeyPatch()
    import fem.core.model

    patches.setattr(fem.core.model.Model, "system", _started)
    yield {"base": base, "model": str(cyl8)}
    patches.undo()
    os.chdir(cwd)


def refused(work, argv) -> None:
    before = snapshot(work["base"])
    try:
        code, _, err, _ = cli(*argv)
    except Started:
        raise AssertionError(f"accepted up to the factorisation: {argv}") from None
    assert "Traceback" not in err, (argv, err)
    assert code == 2, (argv, code, err)
    lines = [line for line in err.splitlines() if line.strip()]
    assert len(lines) == 1 and lines[0].startswith("error: "), (argv, err)
    assert snapshot(work["base"]) == before, (argv, snapshot(work["base"]) - before)


numbers = st.floats(allow_nan=False, allow_infinity=False, min_value=-1e6, max_value=1e6).map(lambda v: f"{v:g}")
NON_FINITE = st.sampled_from(["nan", "inf", "-inf", "NaN", "1e400"])
TOO_MANY = st.tuples(st.floats(0, 1), st.floats(1e3, 1e300), st.floats(1e-300, 1e-3)).map(
    lambda t: f"{t[0]:g}:{t[1]:g}:{t[2]:g}")                          # more than 100,000 values
BEYOND = st.floats(TISSUE_MM + 0.01, 1e9).map(lambda v: f"{v:g}")     # past the tissue over the bone
GARBAGE = st.sampled_from(["", " ", "abc", "1,,2", "1:2", "1:2:3:4", "2:1:0.5", "0:1:0", "0:1:-1", "a,b", "1;2"])


def value_list(bad_value):
    """A value list in one of its forms with one bad value in it."""
    return st.one_of(bad_value, st.tuples(numbers, bad_value).map(lambda t: f"{t[0]},{t[1]}"),
                     st.tuples(bad_value, numbers).map(lambda t: f"0:{t[0]}:{t[1]}"))


DEPTHS = st.one_of(value_list(NON_FINITE), TOO_MANY, GARBAGE, BEYOND,
                   st.floats(-1e9, -1e-9).map(lambda v: f"{v:g}"),
                   st.tuples(st.floats(0.01, 1), st.floats(TISSUE_MM + 0.6, 1e4)).map(
                       lambda t: f"{t[0]:g}:{t[1]:g}:0.5"))                  # its last depth past the tissue
SWEEPS = st.one_of(st.tuples(st.sampled_from(["x", "z"]), st.one_of(value_list(NON_FINITE), TOO_MANY, GARBAGE)).map(
    lambda t: f"{t[0]}={t[1]}"), st.sampled_from(["y=0:1:1", "q", "x", "=1", "z=-1:1:0.5"]))
RECEPTOR_DEPTHS = st.one_of(value_list(NON_FINITE), GARBAGE, BEYOND, st.just("0.001:2:0.001"),
                            st.floats(-1e6, 0).map(lambda v: f"{v:g}"))
MAX_DEPTHS = st.one_of(NON_FINITE, GARBAGE, BEYOND, st.floats(-1e6, 0).map(lambda v: f"{v:g}"))
FORCES = st.one_of(NON_FINITE, GARBAGE, st.floats(-1e6, 0).map(lambda v: f"{v:g}"))


@SETTINGS
@given(case=st.one_of(
    DEPTHS.map(lambda v: ["--depth", v]),
    SWEEPS.map(lambda v: ["--depth", "0.5", "--sweep", v]),
    RECEPTOR_DEPTHS.map(lambda v: ["--depth", "0.5", "--receptor-depths", v]),
    MAX_DEPTHS.map(lambda v: ["--force", "0.002", "--max-depth", v]),
    FORCES.map(lambda v: ["--force", v])))
def test_bad_value_lists(work, case):
    refused(work, ["indent", work["model"], "--indentor", "C5", *case, "--out", "out", "--quiet"])


BAD_OUTS = st.sampled_from(["", " ", "a_file", "a_file/sub", "/proc/x", "mine", "mine/notes.txt"])
BAD_MODELS = st.sampled_from(["", "a_file", "nosuch", "empty_dir", "mine", "/proc/x"])
BAD_SCENES = st.sampled_from(["", "a_file", "nosuch.toml", "empty_dir", "mine/notes.txt", "mine"])


@SETTINGS
@given(case=st.one_of(
    BAD_OUTS.map(lambda v: {"out": v}), BAD_MODELS.map(lambda v: {"model": v}), BAD_SCENES.map(lambda v: {"scene": v})))
def test_bad_paths(work, case):
    experiment = ["--scene", case["scene"]] if "scene" in case else ["--indentor", "C5", "--depth", "0.5"]
    refused(work, ["indent", case.get("model", work["model"]), *experiment, "--out", case.get("out", "out"),
                   "--quiet"])
