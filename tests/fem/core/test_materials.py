"""Materials: the mABCDE code, explicit moduli, per-layer Poisson ratio, rigid bone, refusals."""
import numpy as np
import pytest

from fem import InputError, Material
from fem.core.materials import default_code


def test_material_code_and_explicit_moduli():
    m = Material("m43338", nu=0.48)
    assert m.E_MPa == {1: 0.01, 2: 0.001, 3: 0.001, 4: 0.001, 5: 100.0}
    assert Material({1: 0.01, 2: 2.0}, nu={1: 0.3, 2: 0.4999}).nu[2] == 0.4999
    mu, lam = Material([0.01]).lame(np.array([1]))
    assert np.isclose(mu[0], 0.01 / (2 * 1.48)) and np.isclose(lam[0], 0.01 * 0.48 / (1.48 * 0.04))
    assert Material("m33338", rigid_bone=True).rigid == {5}


@pytest.mark.parametrize("spec, nu, text", [
    ("m43338", 0.5, "Poisson"), ("m43338", 0.49995, "Poisson"), ("m43338", -0.01, "Poisson"),
    ([0.01, 0.0], 0.48, "positive"), ({1: -2.0}, 0.48, "positive"), ([float("nan")], 0.48, "positive"),
    ("43338", 0.48, "mABCDE"), ("m4a", 0.48, "mABCDE"), ({1: 0.01, 2: 0.1}, {1: 0.3}, "layers [2]"),
])
def test_refused(spec, nu, text):
    with pytest.raises(InputError) as exc:
        Material(spec, nu=nu)
    assert text in str(exc.value) and "\n" not in str(exc.value)


def test_missing_layer_refused():
    with pytest.raises(InputError, match=r"layers \[7\]"):
        Material({1: 0.01, 5: 100.0}).lame(np.array([1, 7]))    # layer 6 is the fluid, needing no modulus


@pytest.mark.parametrize("spec, layers", [
    ("m3", [1]), ("m33338", [1, 5]), ("m43338", [1, 2, 3, 4, 5]), ("m3", [1, 6]), ([0.001], [1]),
    ([0.001, 0.001, 0.001, 0.001, 100.0], [1, 5]), ({1: 0.001, 5: 100.0, 6: 1.0}, [1, 5]),
])
def test_material_fits_its_layers(spec, layers):
    """One digit (or modulus of a list) per layer 1 to the highest solid layer; a mapping names its own."""
    Material(spec).check_layers(layers)
    mu, _ = Material(spec).lame(np.array(layers))
    assert np.all(mu[np.array(layers) != 6] > 0)


@pytest.mark.parametrize("spec, layers, text", [
    ("m433310", [1, 2, 3, 4, 5], "material m433310 has 6 digits but this model has layers 1-5: give 5 digits "
                                 "(digit k = log10 of layer k's modulus in Pa), e.g. m43338"),
    ("m33338", [1], "material m33338 has 5 digits but this model has layer 1 only: give 1 digit"),
    ("m3", [1, 5], "has 1 digit but this model has layers 1 and 5: give 5 digits (digit k = log10 of layer k's "
                   "modulus in Pa; layers 2-4: not in this model, any value), e.g. m33338"),
    ("m33", [1, 6], "layer 1 only (and the fluid core, layer 6, which takes none): give 1 digit"),
    ([0.01, 0.001], [1, 2, 3, 4, 5], "material [0.01, 0.001] gives 2 moduli but this model has layers 1-5: "
                                     "give 5 moduli in MPa, one per layer 1-5, e.g. [0.01, 0.001, 0.001, 0.001, 100]"),
    ([0.01] * 6, [1, 5], "gives 6 moduli but this model has layers 1 and 5: give 5 moduli"),
])
def test_material_of_other_layers_refused(spec, layers, text):
    """A code or list with more or fewer values than the model's layers is one line naming them
    (the six-digit code meant as a 1e10 Pa bone would give a 10 Pa bone and a sixth layer)."""
    for check in (lambda m: m.check_layers(layers), lambda m: m.lame(np.array(layers))):
        with pytest.raises(InputError) as exc:
            check(Material(spec))
        assert text in str(exc.value) and "\n" not in str(exc.value)


def test_default_code_per_layers():
    assert [default_code(k) for k in ([1], [1, 5], [1, 2, 3, 4, 5], [1, 6])] == ["m3", "m33338", "m43338", "m3"]
    for layers in ([1], [1, 5], [1, 2, 3, 4, 5], [1, 6]):
        Material(default_code(layers)).check_layers(layers)
