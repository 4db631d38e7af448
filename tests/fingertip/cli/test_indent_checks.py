"""`indent` guards: a material code with one digit per layer of the model (else one error line naming
the layers, before any work), and the linear range of a run (element inversion, receptor strain)
in run.json and the summary."""
import json

import pytest

from fem.experiments.runner import LARGE_DEFORMATION, LINEAR_ENOUGH_MM
from tests.helpers import cli, snapshot


def _one_error(ran) -> str:
    err = ran.err.strip()
    assert ran.code == 2 and err.startswith("error: ") and "\n" not in err, ran.err
    return err


def test_six_digit_code_refused_on_five_layer_model(section, tmp_path):
    """m433310 (meant: a 1e10 Pa bone) would be six layers with a 10 Pa bone: refused, naming the
    option and the model's layers, before the model is read (no lock, no output, no response model)."""
    scene = tmp_path / "s.toml"
    scene.write_text('material = [0.01, 0.001, 0.001, 0.001]\n[[experiment]]\nindentor = "C5"\ndepth_mm = 0.5\n')
    before = snapshot(section, tmp_path)
    out = tmp_path / "bad"
    err = _one_error(cli("indent", section, "--indentor", "C5", "--depth", "0.5", "--material", "m433310",
                         "--out", out))
    assert err == ("error: --material m433310 has 6 digits but this model has layers 1-5: give 5 digits (digit "
                   "k = log10 of layer k's modulus in Pa), e.g. m43338")
    err = _one_error(cli("prepare", section, "--material", "m4333"))
    assert "--material m4333 has 4 digits but this model has layers 1-5" in err
    err = _one_error(cli("indent", section, "--scene", scene, "--out", out))
    assert "error: material [0.01, 0.001, 0.001, 0.001] gives 4 moduli but this model has layers 1-5: give 5" in err
    assert snapshot(section, tmp_path) == before


@pytest.mark.parametrize("material", ["m33338", "m43338", "m43339"])
def test_codes_that_fit_accepted(cyl8, tmp_path, material):
    """Five digits on the cylinder with bone (layers 1 and 5; digits 2-4 stand for no elements)."""
    out = tmp_path / "ok"
    ran = cli("indent", cyl8, "--indentor", "C5", "--depth", "0.25", "--material", material, "--no-plots",
              "--no-pvd", "--out", out, "--quiet")
    assert ran.code == 0, ran.err
    assert json.loads((out / "run.json").read_text())["material"] == material


def test_deep_wedge_inverts_elements_shallow_cylinder_does_not(cyl8, tmp_path):
    """A sharp wedge 2.5 mm into the cylinder with bone (3 mm of tissue over the bone) turns about
    1 % of the elements inside out and strains receptors by more than 1: run.json and the summary
    say so, and the warning is logged; C5 0.25 mm deep stays in the linear range (receptor strains
    0.1) and warns of nothing, but notes, in one line, that it goes deeper than where linear and
    finite kinematics part by 5 % for cylinders. Both with --pvd: the factorised run has the full field the inversion
    check needs (a stored response model does not: the next test)."""
    deep, shallow = tmp_path / "deep", tmp_path / "shallow"
    ran = cli("indent", cyl8, "--indentor", "wedge", "--depth", "1,2.5", "--no-plots", "--pvd", "--out", deep)
    assert ran.code == 0, ran.err
    v = json.loads((deep / "run.json").read_text())["experiments"][0]["validity"]
    assert v["checked_indentation"] == 1 and v["depth_mm"] == 2.5 and v["inversion_checked"]
    assert 0.002 < v["inverted_elements"] < 0.05 and v["max_receptor_strain"] > 1.0
    assert v["max_linear_strain"] == 0.2 and not v["within_linear_range"]
    line = [t for t in ran.out.splitlines() if "warning:" in t]
    assert len(line) == 1 and line[0].startswith("  warning: wedge at 2.5 mm: the linear displacement inverts ")
    assert "% of the elements and strains receptors by" in line[0] and "(> 0.2)" in line[0]
    assert line[0].endswith(LARGE_DEFORMATION)
    assert line[0].strip() in ran.err.splitlines()                  # the module logger's line on stderr
    ran = cli("indent", cyl8, "--indentor", "C5", "--depth", "0.1,0.25", "--no-plots", "--pvd", "--out", shallow)
    assert ran.code == 0 and "warning" not in ran.out + ran.err
    v = json.loads((shallow / "run.json").read_text())["experiments"][0]["validity"]
    assert v["inverted_elements"] == 0.0 and v["max_receptor_strain"] < 0.2 and v["within_linear_range"]
    assert v["linear_enough_mm"] == LINEAR_ENOUGH_MM[2]["cylinder"] < 0.25
    notes = [t for t in ran.out.splitlines() if "note:" in t]
    assert len(notes) == 1 and notes[0].startswith(f"  note: C5 reaches 0.25 mm: beyond {v['linear_enough_mm']:.2g} mm")
    assert "for cylinders" in notes[0] and notes[0].endswith("--kinematics finite for large-deformation numbers")


def test_stored_response_model_leaves_inversion_unchecked(cyl8, tmp_path):
    """Answered from a stored response model (no full field): receptor strains are checked,
    inversion is not, and the summary says so."""
    assert cli("prepare", cyl8, "--quiet").code == 0
    out = tmp_path / "stored"
    ran = cli("indent", cyl8, "--indentor", "wedge", "--depth", "2.5", "--no-plots", "--no-pvd", "--out", out)
    assert ran.code == 0 and "response model: stored" in ran.out, ran.err
    v = json.loads((out / "run.json").read_text())["experiments"][0]["validity"]
    assert v["inverted_elements"] is None and not v["inversion_checked"] and v["max_receptor_strain"] > 1.0
    assert "element inversion not checked: a stored response model has no full displacement field" in ran.out


def test_indentor_classes_and_their_linear_depth():
    """Each indentor code falls in its LINEAR_ENOUGH_MM class; codes of no measured class take the
    smallest depth of their dimension."""
    from fem.experiments.runner import indentor_class, linear_enough_mm
    classes = {"C1": "cylinder", "cylinder:3": "cylinder", "R1": "bar", "bar:2": "bar", "sphere:2": "sphere",
               "step:0": "step", "step:1.2,0.4": "step", "plate": None, "punch": None, "grating:1": None,
               "wedge": None, "ellipsoid:1,2,3": None, "two-point:3:1": None}
    for code, cls in classes.items():
        assert indentor_class(code) == cls, code
        for dim in (2, 3):
            table = LINEAR_ENOUGH_MM[dim]
            assert linear_enough_mm(code, dim) == table.get(cls, min(table.values()))
