"""Generated bad input (hypothesis) at every subcommand: option values and file contents.

Every run through `pipeline.main` ends with exit code 0 or 2, never a traceback; exit 2 comes
with exactly one `error:` line on stderr and no new file anywhere in the work folder. Inputs
that pass every check would start a long computation: the first factorisation, meshing,
reconstruction or fit raises `Started` instead, which counts as accepted (the checks that can
run without that work all ran before it).
"""
from __future__ import annotations

import json
import os
import shutil
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from tests.helpers import ROOT, cli, snapshot

SETTINGS = settings(max_examples=60, deadline=None, derandomize=True, database=None,
                    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])


class Started(BaseException):
    """Raised where a long computation would begin: the input passed every check before it."""


def _started(*args, **kwargs):
    raise Started


WORDS = ["-1", "0", "-0.01", "0.5", "2", "nan", "inf", "-inf", "1e308", "1e-308", "abc", "", " ", "1,2",
         "0:1:0", "2:1:0.5", "1:2", "1:2:3:4", "x=1", "z=-1:1:0.5", "y=0:1:1", "C9", "C5", "cylinder:-2",
         "wedge:abc", "wedge:95", "two-point:x", "two-point:-1", "grating:0", "step:9", "sphere:nan",
         "ellipsoid:1,2", "m4", "m12345", "m43338", "mXYZ", "perpendicular", "parallel", "45", "top",
         "z=middle", "x=nan", "1,,2", "a,b", "99"]
VALUES = st.one_of(
    st.sampled_from(WORDS),
    st.text(st.characters(blacklist_categories=("Cs",), blacklist_characters="\x00"), max_size=8),
    st.floats(allow_nan=True, allow_infinity=True).map(repr),
    st.integers(-10**9, 10**9).map(str))


@pytest.fixture(scope="module")
def work(tmp_path_factory):
    """A 2D cylinder8 model, a run folder of it, a tiny turntable folder; cwd is the work folder
    (relative paths drawn stay inside it); the long computations raise Started."""
    base = tmp_path_factory.mktemp("generated")
    cwd = os.getcwd()
    os.chdir(base)
    model = base / "cyl8"
    assert cli("mesh", "--preset", "cylinder8", "--bone", "--out", model, "--quiet").code == 0
    assert cli("indent", model, "--indentor", "C5", "--depth", "0.5", "--out", base / "run", "--quiet",
               "--no-pvd").code == 0
    tt = base / "turntable"
    tt.mkdir()
    for p in sorted((ROOT / "sample_images").iterdir())[:5]:
        shutil.copy(p, tt / p.name)
    (base / "a_file").write_text("x\n")
    patches = pytest.MonkeyPatch()
    import fem.core.model
    import fem.geometry.mesh2d
    import fem.geometry.mesh3d
    import reconstruct.pipeline

    patches.setattr(fem.core.model.Model, "system", _started)
    patches.setattr(fem.geometry.mesh3d, "build_mesh", _started)
    patches.setattr(fem.geometry.mesh2d, "run_mesh2d", _started)
    patches.setattr(reconstruct.pipeline, "reconstruct", _started)
    patches.setenv("FINGERTIP_CACHE_DIR", str(base / "cache"))
    yield base
    patches.undo()
    os.chdir(cwd)


def check(base: Path, argv) -> None:
    """The promise of the command line for one argv."""
    before = snapshot(base)
    code, _, err, _ = cli(*argv, accept=Started)
    assert "Traceback" not in err, (argv, err)
    assert code in (0, 2), (argv, code, err)
    if code == 2:
        lines = [line for line in err.splitlines() if line.strip()]
        assert len(lines) == 1 and lines[0].startswith("error: "), (argv, err)
        assert snapshot(base) == before, (argv, snapshot(base) - before)
    for new in snapshot(base) - before:                     # an accepted run's outputs: start clean again
        if new.exists() and new.parent in before | {base}:
            shutil.rmtree(new) if new.is_dir() else new.unlink()


def options(names):
    """A few (option, value) pairs of these option names."""
    return st.lists(st.tuples(st.sampled_from(names), VALUES), max_size=3).map(lambda kv: [w for p in kv for w in p])


OUTS = st.sampled_from(["out", "a_file", "a_file/sub", "/proc/x", "cyl8"])


@SETTINGS
@given(extra=options(["--size", "--coarse", "--growth", "--fine-depth", "--epidermis", "--dermis", "--layer3",
                      "--layer3-scale", "--bone-diameter", "--bone-profile", "--bone-offset", "--nail-span",
                      "--support-span", "--support-incline", "--tip", "--tip-width-frac", "--section-z",
                      "--preset"]),
       preset=st.sampled_from(["cylinder8", "monkey", "square", "nosuch"]), out=OUTS)
def test_mesh_options(work, extra, preset, out):
    check(work, ["mesh", "--preset", preset, "--out", out, "--quiet", *extra])


@SETTINGS
@given(doc=st.one_of(st.binary(max_size=80),
                     st.recursive(st.none() | st.booleans() | st.floats() | st.text(max_size=5),
                                  lambda c: st.lists(c, max_size=3) | st.dictionaries(
                                      st.sampled_from(["sections", "z_mm", "points", "version", "x"]), c,
                                      max_size=3), max_leaves=8).map(lambda d: json.dumps(d).encode())))
def test_mesh_sections_file(work, doc):
    src = work / "src"
    src.mkdir(exist_ok=True)
    (src / "sections.json").write_bytes(doc)
    check(work, ["mesh", src, "--out", "out", "--quiet"])


INDENT_OPTIONS = ["--indentor", "--axis", "--position", "--incline", "--depth", "--force", "--max-depth", "--sweep",
                  "--material", "--nu", "--receptor-depths", "--receptor-spacing", "--line"]


@SETTINGS
@given(extra=options(INDENT_OPTIONS), out=OUTS)
def test_indent_options(work, extra, out):
    check(work, ["indent", work / "cyl8", "--indentor", "C5", "--depth", "0.5", "--out", out, "--quiet", *extra])


KEYS = ["indentor", "depth_mm", "force_N", "orientation", "position_mm", "sweep", "max_depth_mm", "incline_deg",
        "name", "start", "approach", "equal_force"]
TOML_VALUES = st.sampled_from(['"C5"', '"wedge:abc"', "-1", "0.5", '"0:1:0.1"', '"zero"', "nan", "inf", "[1, 2]",
                               '[1, "a"]', "true", '"x=-1:1:0.5"', '"perpendicular"', '"top"', "{a = 1}", "[]"])


@SETTINGS
@given(text=st.one_of(
    st.binary(max_size=80),
    st.lists(st.tuples(st.sampled_from(KEYS), TOML_VALUES), max_size=5).map(
        lambda kv: ("[[experiment]]\n" + "".join(f"{k} = {v}\n" for k, v in dict(kv).items())).encode()),
    st.tuples(st.sampled_from(["[receptors]", "[output]", ""]),
              st.sampled_from(["depths_mm", "spacing_mm", "line", "measures", "pvd", "material", "nu"]),
              TOML_VALUES).map(lambda t: (f'{t[0]}\n{t[1]} = {t[2]}\n[[experiment]]\nindentor = "C5"\n'
                                          f'depth_mm = 0.5\n').encode())))
def test_indent_scene_file(work, text):
    scene = work / "scene.toml"
    scene.write_bytes(text)
    check(work, ["indent", work / "cyl8", "--scene", scene, "--out", "out", "--quiet"])


@SETTINGS
@given(doc=st.one_of(st.binary(max_size=60),
                     st.dictionaries(st.sampled_from(["kind", "material", "nu", "params", "regions"]),
                                     st.none() | st.floats() | st.text(max_size=4) | st.lists(st.integers(), max_size=2),
                                     max_size=3).map(lambda d: json.dumps(d).encode())),
       command=st.sampled_from([["indent", "--indentor", "C5", "--depth", "0.5"], ["line-load", "--depth", "0.5"],
                                ["contact-series", "--force", "0.01"]]))
def test_model_json(work, doc, command):
    model = work / "broken_model"
    model.mkdir(exist_ok=True)
    shutil.copy(work / "cyl8" / "mesh.vtu", model / "mesh.vtu")
    (model / "model.json").write_bytes(doc)
    check(work, [command[0], model, *command[1:], "--out", "out", "--quiet"])


def _csv(columns):
    """Random bytes, or a CSV of these (and wrong) columns with odd values."""
    cell = st.sampled_from(["1", "-1", "0", "nan", "", "a", "1e9", "0.5", "inf"])
    header = st.lists(st.sampled_from([*columns, "x", ""]), min_size=1, max_size=len(columns) + 1)
    table = st.tuples(header, st.lists(st.lists(cell, min_size=1, max_size=len(columns) + 1), max_size=4)).map(
        lambda t: (",".join(t[0]) + "\n" + "".join(",".join(r) + "\n" for r in t[1])).encode())
    return st.one_of(st.binary(max_size=80), table)


@SETTINGS
@given(command=st.sampled_from(["study-layers", "fit-material"]),
       csv=_csv(["distance_mm", "deflection_mm", "depth_mm"]),
       extra=options(["--layers", "--offsets", "--depth", "--base", "--indentor", "--axis", "--position", "--nu",
                      "--free-layers", "--bounds", "--noise", "--side", "--match"]), out=OUTS)
def test_deflection_commands(work, command, csv, extra, out):
    (work / "deflection.csv").write_bytes(csv)
    check(work, [command, work / "cyl8", "--deflection", "deflection.csv", "--out", out, "--quiet", *extra])


@SETTINGS
@given(csv=_csv(["depth_mm", "force_N"]), extra=options(["--force-indentor", "--bounds", "--match", "--material"]))
def test_force_csv(work, csv, extra):
    (work / "force.csv").write_bytes(csv)
    check(work, ["fit-material", work / "cyl8", "--force", "force.csv", "--out", "out", "--quiet", *extra])


@SETTINGS
@given(command=st.sampled_from([["line-load", "--depth", "0.5"], ["contact-series", "--force", "0.01"]]),
       extra=options(["--depth", "--material", "--nu", "--half-width", "--half-length", "--step", "--position",
                      "--force", "--cylinders", "--axis"]), out=OUTS)
def test_line_load_and_contact_series(work, command, extra, out):
    check(work, [command[0], work / "cyl8", *command[1:], "--out", out, "--quiet", *extra])


@SETTINGS
@given(csv=_csv(["stimulus", "position_mm", "rate_ips", "unit", "orientation"]),
       extra=options(["--measures", "--fit-on", "--orientation", "--receptor-x", "--diameters"]), out=OUTS)
def test_analyze(work, csv, extra, out):
    (work / "neural.csv").write_bytes(csv)
    check(work, ["analyze", work / "run", "--neural", "neural.csv", "--out", out, "--quiet", *extra])


@SETTINGS
@given(toml=st.one_of(st.binary(max_size=60),
                      st.tuples(st.sampled_from(["start_deg", "step_deg", "template_diameter_mm", "axis",
                                                 "volar_view_deg", "views"]), TOML_VALUES).map(
                          lambda t: f"{t[0]} = {t[1]}\n".encode())))
def test_turntable_manifest(work, toml):
    (work / "turntable" / "turntable.toml").write_bytes(toml)
    check(work, ["reconstruct", work / "turntable", "--out", "out", "--quiet"])


@SETTINGS
@given(size=VALUES, scene=st.sampled_from([None, "a_file", "nosuch.toml"]), out=OUTS)
def test_run_chain(work, size, scene, out):
    check(work, ["run", ROOT / "sample_images", "--out", out, "--size", size, "--quiet",
                 *(["--scene", scene] if scene else [])])
