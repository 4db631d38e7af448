"""Materials: the mABCDE code, explicit moduli, per-layer Poisson ratio, rigid bone, refusals."""
import numpy as np
import pytest

from fem import InputError, Material


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
        Material("m43338").lame(np.array([1, 7]))               # layer 6 is the fluid, needing no modulus
