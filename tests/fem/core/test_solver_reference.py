"""Solver against closed forms: Flamant, Boussinesq, thesis appendices A and B, two-material bar
and layered block (interface tractions continuous, strains jump by the modulus ratio)."""
import numpy as np
import pytest

from fem import Model
from fem.verify import closed_forms as ref

E = 0.01   # MPa
DEPTHS = (0.5, 0.75, 1.0)


def test_flamant_line_load():
    """Half disc R = 200 mm (far edge fixed), P = 0.01 N/mm spread over |x| < 0.01 mm, nu = 0.48.
    Stresses at 0.5-1.0 mm depth, x = 0-0.5 mm, within 3 % of sigma_yy (measured <= 1.2 %)."""
    P = 0.01
    pts, cells, regions = ref.half_disc(0.01, 200.0, n_rad=60, n_arc=48, ratio=1.2)
    model = Model(pts, cells, np.ones(len(cells)), regions, material=[E], nu=0.48)
    sol = model.solve(prescribed={"far": 0.0}, forces={"patch": (0.0, -P)})
    x = np.array([[dx, -d] for d in DEPTHS for dx in (0.0, 0.25, 0.5)])
    f = sol.fields(x)
    sxx, syy, sxy = ref.flamant(x[:, 0], x[:, 1], P)
    np.testing.assert_allclose(f["stress_yy_MPa"], syy, rtol=0.03)
    scale = np.abs(syy)
    assert np.all(np.abs(f["stress_xx_MPa"] - sxx) < 0.03 * scale)
    assert np.all(np.abs(f["stress_xy_MPa"] - sxy) < 0.03 * scale)
    np.testing.assert_allclose(sol.force("far"), [0.0, P], rtol=1e-9, atol=1e-12)


def test_boussinesq_point_load():
    """Quarter of the half-space (symmetry planes x = 0 and z = 0) between radii 0.1 and 3 mm:
    the point load is the exact Boussinesq traction on the 0.1 mm cavity around it, the far
    surface carries the exact displacement. Stresses at 0.5-1.0 mm depth within 3 % of the
    largest stress component there (measured <= 2.5 % on this 23k-DOF mesh; 1.8 % at 52k DOFs)."""
    P, nu = 0.01, 0.48
    pts, cells, regions = ref.sphere_octant_shell(0.1, 3.0, n_arc=10, n_rad=16, ratio=1.12)
    pts = pts * [1, -1, 1]                                        # body in y < 0
    model = Model(pts, cells, np.ones(len(cells)), regions, material=[E], nu=nu)

    def traction(x, n):
        return np.einsum("...ij,j...->i...", ref.boussinesq(x[0], x[1], x[2], P, E, nu)[1], n)

    sol = model.solve(prescribed={"sym_x": (0, None, None), "sym_z": (None, None, 0),
                                  "outer": lambda x: ref.boussinesq(x[:, 0], x[:, 1], x[:, 2], P, E, nu)[0]},
                      tractions={"inner": traction})
    x = np.array([[a, -d, c] for d in DEPTHS for a, c in ((0.0, 0.0), (0.3, 0.0), (0.2, 0.4))])
    f = sol.fields(x)
    _, s = ref.boussinesq(x[:, 0], x[:, 1], x[:, 2], P, E, nu)
    scale = np.abs(s).reshape(len(x), -1).max(axis=1)
    for name in ("xx", "yy", "zz", "yz", "xz", "xy"):
        i, j = "xyz".index(name[0]), "xyz".index(name[1])
        assert np.all(np.abs(f[f"stress_{name}_MPa"] - s[:, i, j]) < 0.03 * scale), name
    assert sol.residual < 1e-10


def test_appendix_b_strains_independent_of_E_forces_scale_with_E():
    """Homogeneous model, loading by prescribed displacement only (2D and 3D)."""
    for dims in ((np.linspace(0, 4, 9), np.linspace(0, 2, 5)),
                 (np.linspace(0, 2, 5), np.linspace(0, 1, 3), np.linspace(0, 1, 3))):
        pts, cells, regions = ref.box(*dims)
        patch = regions["ymax"] & (np.abs(pts[:, 0] - pts[:, 0].max() / 2) < 0.6)
        regions = {"base": regions["ymin"], "patch": patch}
        d = len(dims)
        push = tuple([0.0] * (d - 1)) + (-0.1,) if d == 2 else (0.0, -0.1, 0.0)
        out = []
        for modulus in (0.01, 1.0):
            model = Model(pts, cells, np.ones(len(cells)), regions, material=[modulus], nu=0.48)
            sol = model.solve(prescribed={"base": 0.0, "patch": push})
            out.append((sol.element_fields, sol.force("patch")))
        (f1, F1), (f2, F2) = out
        for name in ("strain_xx", "strain_yy", "strain_xy", "max_compressive_strain"):
            np.testing.assert_allclose(f2[name], f1[name], rtol=1e-8, atol=1e-12)
        np.testing.assert_allclose(F2, 100 * F1, rtol=1e-8)
        np.testing.assert_allclose(f2["sed_MPa"], 100 * f1["sed_MPa"], rtol=1e-8)
        assert F1[1] < 0            # the patch is pushed down


@pytest.mark.parametrize("nu, tol", [(0.49, 0.02), (0.499, 2e-3), (0.4999, 2e-4)])
def test_appendix_a_plane_strain_sed_tends_to_two_thirds_E_eps1_squared(nu, tol):
    """Plane strain, nu -> 0.5: SED -> (2/3) E eps1^2 with eps1 the max compressive strain.
    Checked pointwise on the (non-uniform) Flamant field; the relative gap is O(1 - 2 nu)."""
    pts, cells, regions = ref.half_disc(0.01, 50.0, n_rad=40, n_arc=32, ratio=1.25)
    model = Model(pts, cells, np.ones(len(cells)), regions, material=[E], nu=nu)
    sol = model.solve(prescribed={"far": 0.0}, forces={"patch": (0.0, -0.01)})
    x = np.array([[dx, -d] for d in DEPTHS for dx in (0.0, 0.4, 1.0)])
    f = sol.fields(x, ["sed_MPa", "max_compressive_strain"])
    target = ref.plane_strain_sed_incompressible(E, f["max_compressive_strain"])
    gap = np.abs(f["sed_MPa"] / target - 1)
    assert np.all(gap < tol)
    assert np.all(gap > 0.1 * (1 - 2 * nu))      # not trivially equal: the gap closes as nu -> 0.5


@pytest.mark.parametrize("dim", [2, 3])
@pytest.mark.parametrize("code", ["m43", "m49"])          # contrast 10 and 1e6
def test_two_material_bar(dim, code):
    """Bar along x, layer 1 for x < 1, layer 2 for x > 1, lateral faces on rollers, end traction t:
    sigma_xx = t in both, eps_xx = t / M_k (M = lambda + 2 mu): the strain jumps by E2 / E1."""
    grids = [np.linspace(0, 2, 9)] + [np.linspace(0, 0.5, 3)] * (dim - 1)
    pts, cells, regions = ref.box(*grids)
    layer = np.where(pts[cells].mean(axis=1)[:, 0] < 1.0, 1, 2)
    t = -1e-4
    rollers = {"xmin": (0,) + (None,) * (dim - 1)}
    for i, c in enumerate("yz"[:dim - 1]):
        spec = [None] * dim
        spec[i + 1] = 0
        rollers[f"{c}min"] = rollers[f"{c}max"] = tuple(spec)
    model = Model(pts, cells, layer, regions, material=code, nu=0.48)
    sol = model.solve(prescribed=rollers, tractions={"xmax": (t,) + (0.0,) * (dim - 1)})
    x = np.array([[0.999999, 0.2, 0.2], [1.000001, 0.2, 0.2]])[:, :dim]
    left, right = (sol.fields(x[k:k + 1], ["stress_xx_MPa", "strain_xx"], layer=k + 1) for k in (0, 1))
    np.testing.assert_allclose([left["stress_xx_MPa"][0], right["stress_xx_MPa"][0]], t, rtol=1e-8)
    E1, E2 = (model.material.E_MPa[k] for k in (1, 2))
    np.testing.assert_allclose(left["strain_xx"][0] / right["strain_xx"][0], E2 / E1, rtol=1e-7)
    assert sol.residual < 1e-8


@pytest.mark.parametrize("dim", [2, 3])
def test_layered_block_interface_tractions_continuous(dim):
    """Three layers stacked in y (skin-like, moduli 1e4, 1e3, 1e9 Pa: contrast 1e6), base fixed,
    top traction (shear tau, pressure q), side faces carrying the exact piecewise-uniform stress.
    sigma_yy, sigma_xy continuous at the interfaces; eps_xy jumps by mu ratio, eps_yy by M ratio."""
    tau, q, nu = 2e-4, 5e-4, 0.48
    grids = [np.linspace(0, 1, 5), np.linspace(0, 1.5, 7)] + [np.linspace(0, 1, 3)] * (dim - 2)
    pts, cells, regions = ref.box(*grids)
    yc = pts[cells].mean(axis=1)[:, 1]
    layer = np.where(yc > 1.0, 1, np.where(yc > 0.5, 2, 3))
    model = Model(pts, cells, layer, regions, material="m439", nu=nu)
    lam_over_M = nu / (1 - nu)                       # sigma_xx / sigma_yy under lateral confinement

    def side(sign):
        def traction(x, n):
            t = np.zeros_like(x)
            t[0] = -q * lam_over_M * n[0]
            t[1] = tau * n[0]
            return t
        return traction

    top = (tau, -q) + (0.0,) * (dim - 2)
    sides = {"xmin": side(-1), "xmax": side(1)}
    prescribed = {"ymin": 0.0}
    if dim == 3:
        prescribed.update({"zmin": (None, None, 0), "zmax": (None, None, 0)})
    sol = model.solve(prescribed=prescribed, tractions={"ymax": top, **sides})
    for y_if, (above, below) in ((1.0, (1, 2)), (0.5, (2, 3))):
        x = np.array([[0.5, y_if, 0.5][:dim]])
        fa = sol.fields(x, layer=above)
        fb = sol.fields(x, layer=below)
        for name, exact in (("stress_yy_MPa", -q), ("stress_xy_MPa", tau)):
            np.testing.assert_allclose([fa[name][0], fb[name][0]], exact, rtol=1e-6)
        Ea, Eb = model.material.E_MPa[above], model.material.E_MPa[below]
        np.testing.assert_allclose(fa["strain_xy"][0] / fb["strain_xy"][0], Eb / Ea, rtol=1e-6)
        np.testing.assert_allclose(fa["strain_yy"][0] / fb["strain_yy"][0], Eb / Ea, rtol=1e-6)
