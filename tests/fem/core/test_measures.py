"""Measures registry and point sampling: values on known tensors, names and units, sampling in the
element that holds the point (never averaged across a layer interface)."""
import numpy as np
import pytest

from fem import InputError, Model
from fem.core.measures import MEASURES, State, check_names, describe, evaluate
from fem.verify import closed_forms as ref


def test_registry_names_carry_units():
    for name, m in MEASURES.items():
        assert m.unit in ("1", "mm", "MPa")
        assert name.endswith(("_mm", "_MPa")) == (m.unit != "1"), name
    for required in ("sed_MPa", "max_compressive_strain", "max_tensile_strain", "max_shear_strain",
                     "max_shear_stress_MPa", "principal_stress_1_MPa", "principal_stress_3_MPa",
                     "strain_xx", "strain_yy", "strain_zz", "stress_xx_MPa", "stress_yy_MPa",
                     "stress_zz_MPa", "mean_stress_MPa"):
        assert required in MEASURES
    assert len(describe().splitlines()) == len(MEASURES)
    with pytest.raises(InputError, match="unknown measure"):
        check_names(["sed"])


def test_measures_on_a_known_state():
    rng = np.random.default_rng(0)
    R = np.linalg.qr(rng.normal(size=(3, 3)))[0]
    eps_p = np.array([0.02, -0.005, -0.03])
    strain = R @ np.diag(eps_p) @ R.T
    mu, lam = 0.004, 0.08
    stress = 2 * mu * strain + lam * np.trace(strain) * np.eye(3)
    sig_p = 2 * mu * eps_p + lam * eps_p.sum()
    s = State(np.array([[0.1, -0.2, 0.3]]), strain[None], stress[None])
    v = {k: x[0] for k, x in evaluate(None, s).items()}
    np.testing.assert_allclose([v[f"principal_strain_{k}"] for k in (1, 2, 3)], eps_p[[0, 1, 2]], atol=1e-15)
    np.testing.assert_allclose([v[f"principal_stress_{k}_MPa"] for k in (1, 2, 3)], np.sort(sig_p)[::-1], atol=1e-15)
    assert np.isclose(v["max_tensile_strain"], 0.02) and np.isclose(v["max_compressive_strain"], 0.03)
    assert np.isclose(v["max_shear_strain"], 0.025)
    assert np.isclose(v["max_shear_stress_MPa"], 2 * mu * 0.025)
    assert np.isclose(v["sed_MPa"], 0.5 * np.dot(sig_p, eps_p))
    assert np.isclose(v["mean_stress_MPa"], sig_p.mean())
    assert np.isclose(v["volumetric_strain"], eps_p.sum())
    dev = sig_p - sig_p.mean()
    assert np.isclose(v["von_mises_stress_MPa"], np.sqrt(1.5 * (dev**2).sum()))
    assert np.isclose(v["strain_yz"], strain[1, 2]) and np.isclose(v["stress_xz_MPa"], stress[0, 2])
    assert np.isclose(v["displacement_magnitude_mm"], np.sqrt(0.14))


@pytest.fixture(scope="module")
def two_layers():
    pts, cells, regions = ref.box(np.linspace(0, 2, 9), np.linspace(0, 1, 5))
    layer = np.where(pts[cells].mean(axis=1)[:, 1] > 0.5, 1, 2)
    model = Model(pts, cells, layer, regions, material="m43", nu=0.48)
    rollers = {"ymin": 0.0, "xmin": (0.0, None), "xmax": (0.0, None)}       # uniaxial strain
    return model.solve(prescribed=rollers, tractions={"ymax": (0.0, -1e-4)})


def test_sampling_uses_the_holding_element_per_layer(two_layers):
    sol = two_layers
    on_interface = np.array([[1.0, 0.5]])
    stiff = sol.sample("strain_yy", on_interface, layer=1)[0]              # m43: layer 1 1e4 Pa
    soft = sol.sample("strain_yy", on_interface, layer=2)[0]               # layer 2 1e3 Pa
    np.testing.assert_allclose(soft / stiff, 10.0, rtol=1e-6)             # E1 / E2: no averaging
    assert sol.fields(on_interface, ["sed_MPa"])["layer"][0] in (1, 2)
    inside = np.array([[0.3, 0.8], [1.7, 0.2]])
    f = sol.fields(inside, ["strain_yy"])
    assert list(f["layer"]) == [1, 2]
    centroids = sol.model.mesh.p[:, sol.model.mesh.t].mean(axis=1).T
    np.testing.assert_allclose(sol.sample("sed_MPa", centroids), sol.element_fields["sed_MPa"], rtol=1e-12)


def test_points_outside_the_mesh_are_refused(two_layers):
    with pytest.raises(InputError, match="outside"):
        two_layers.sample("sed_MPa", np.array([[0.5, 0.5], [3.0, 0.5]]))
    with pytest.raises(InputError, match="outside layer 2"):
        two_layers.sample("sed_MPa", np.array([[0.5, 0.9]]), layer=2)
    with pytest.raises(InputError, match="unknown measure"):
        two_layers.sample("energy", np.array([[0.5, 0.5]]))
