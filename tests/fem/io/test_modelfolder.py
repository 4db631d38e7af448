"""The model folder's material: fitted to the model's layers where model.json names none or one the
toolkit recorded before codes were checked, refused (naming model.json) where it does not fit."""
import json
import shutil

import numpy as np
import pytest

from fem import InputError
from fem.io.modelfolder import check_folder_material, folder_layers, folder_material, read_model
from tests.helpers import cli

FIVE = {"1": "epidermis", "2": "dermis", "3": "adipose", "4": "fibrous", "5": "bone"}


@pytest.mark.parametrize("info, code", [
    ({"layers": [1], "material": "m33338"}, "m3"),              # a one-layer 2D model recorded m33338
    ({"layers": [1, 6], "material": "m33338"}, "m3"),           # the solid-fluid cylinder: fluid takes none
    ({"layers": [1, 5], "material": "m33338"}, "m33338"),
    ({"layers": FIVE, "material": "m43338"}, "m43338"),          # 3D: model.json's layers are a mapping
    ({"layers": [1]}, "m3"), ({"layers": [1, 5]}, "m33338"), ({"layers": FIVE}, "m43338"),
    ({"layers": [1], "material": "m4"}, "m4"), ({"layers": [1], "material": "m53338"}, "m53338"),
    ({}, "m33338"),
])
def test_folder_material_fits_the_layers(info, code):
    assert folder_material({**info, "nu": 0.45}) == (code, 0.45)


def test_folder_layers():
    assert folder_layers({"layers": [1, 5]}) == [1, 5] and folder_layers({"layers": FIVE}) == [1, 2, 3, 4, 5]
    assert folder_layers({}) == [] and folder_layers({"layers": "x"}) == []


def test_read_model_fits_and_refuses(cyl8, tmp_path):
    """The cylinder with bone (layers 1 and 5) reads with m33338; a one-layer copy of its mesh
    recording m33338 (as the mesher writes it) reads as m3; a code that fits no model of it is
    refused naming model.json, before any assembly."""
    model, _ = read_model(cyl8)
    assert model.material.code == "m33338" and sorted(set(model.layer.tolist())) == [1, 5]
    assert read_model(cyl8, material="m43338")[0].material.code == "m43338"
    with pytest.raises(InputError, match=r"material m433310 has 6 digits but this model has layers 1 and 5: "
                                         r"give 5 digits"):
        read_model(cyl8, material="m433310")
    with pytest.raises(InputError, match=r"material \[0.01, 0.001\] gives 2 moduli but this model has layers "
                                         r"1 and 5: give 5 moduli in MPa"):
        read_model(cyl8, material=(0.01, 0.001))
    folder = tmp_path / "edited"
    shutil.copytree(cyl8, folder)
    info = json.loads((folder / "model.json").read_text())
    (folder / "model.json").write_text(json.dumps({**info, "material": "m4333"}))
    with pytest.raises(InputError) as exc:
        read_model(folder)
    assert "model.json records a material that does not fit its mesh (material m4333 has 4 digits" in str(exc.value)
    assert read_model(folder, material="m43338")[0].material.code == "m43338"     # a given one replaces it


def test_check_folder_material_reads_model_json_only(cyl8, tmp_path):
    folder = tmp_path / "nomesh"
    folder.mkdir()
    (folder / "model.json").write_text((cyl8 / "model.json").read_text())
    (folder / "mesh.vtu").write_text("not read")
    check_folder_material(folder, "m33338")
    check_folder_material(folder, None)
    for material in ("m3", "m333380", (0.01,) * 4):
        with pytest.raises(InputError, match="this model has layers 1 and 5"):
            check_folder_material(folder, material, 0.48)


def test_one_layer_model_default_is_one_digit(tmp_path):
    """A one-layer 2D folder (the cylinder without bone) runs with "m3" where it records m33338."""
    out = tmp_path / "cyl"
    assert cli("mesh", "--preset", "cylinder8", "--size", "0.5", "--out", out, "--quiet").code == 0
    assert json.loads((out / "model.json").read_text())["layers"] == [1]
    model, _ = read_model(out)
    assert model.material.code == "m3" and np.allclose(model.mu, 0.001 / (2 * 1.48))
