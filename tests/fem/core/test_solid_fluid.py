"""Solid-fluid 2D model (thesis 4.6): a solid layer around an incompressible fluid core (layer 6)
with one uniform fluid pressure. Thick ring around a fluid core against its closed form, volume
kept under indentation, much softer than the cylinder with bone, the mesh command's option and
refusals; the block preset holds its sides."""
from __future__ import annotations

import json

import meshio
import numpy as np
import pytest

import pipeline
from fem import Model
from fem.contact.indentors import make_indentor
from fem.contact.linear import ContactModel
from fem.core.materials import FLUID_LAYER
from fem.geometry import mesh2d
from fem.io.modelfolder import factorise, open_model, read_model
from fingertip.errors import InputError
from tests.helpers import cli

SIZE = mesh2d.Sizing2D(size_mm=0.25)        # coarse: the whole file runs in a few seconds


# --------------------------------------------------------------------------- closed form
def test_thick_ring_around_an_incompressible_core():
    """Plane-strain ring a < r < b (E = 0.001 MPa, nu = 0.48) around a fluid core, pressure q on
    r = b. The fluid keeps its area, so u_r(a) = 0: u_r = A (r - a^2 / r) with
    A = -q / (2 (lam + mu) + 2 mu a^2 / b^2), fluid pressure P = -sigma_r(a) =
    q (lam + 2 mu) / ((lam + mu) + mu a^2 / b^2). Uniform 0.25 mm mesh (1,700 triangles).

    Measured (sizes 0.5 / 0.25 / 0.125 mm): fluid pressure within 7e-6 / 1.2e-5 / 3e-6 of P; u_r(b)
    within 0.57 / 0.16 / 0.04 % at every outer node (second order: the faceted circles). Asserted:
    P within 1e-4, P - q (1.7 % of q, the part that depends on the ring) within 1 %, u_r(b)
    within 0.5 %. Rigid motion is held by a pin at (b, 0) and u_y at the opposite outer vertex:
    statically determinate, and uniform pressure on a closed polygon has no resultant and no
    moment, so these supports carry nothing; the rigid motion they allow is fitted out."""
    a, b, E, nu, q = 3.0, 4.0, 0.001, 0.48, 1e-4
    dom = mesh2d.Domain2D("ring", [mesh2d._circle(b), mesh2d._circle(a)], [1, FLUID_LAYER],
                          surface=lambda p: np.ones(len(p), bool), fixed=lambda p: np.zeros(len(p), bool),
                          depth=lambda p: np.zeros(len(p)))
    pts, tri, layer = mesh2d.mesh_domain(dom, mesh2d.Sizing2D(size_mm=0.25, coarse_mm=0.25))
    outer = np.flatnonzero(mesh2d.boundary_points(tri, len(pts)))
    pin = np.flatnonzero(np.isclose(pts[:, 0], b) & np.isclose(pts[:, 1], 0.0))
    roll = outer[[np.argmin(pts[outer, 0])]]
    assert len(pin) == 1 and pts[roll[0], 0] < -0.99 * b
    model = Model(pts, tri, layer, {"outer": outer, "pin": pin, "roll": roll}, material=[E], nu=nu)
    sol = model.solve(prescribed={"pin": 0.0, "roll": (None, 0.0)}, pressures={"outer": q})

    mu, lam = E / (2 * (1 + nu)), E * nu / ((1 + nu) * (1 - 2 * nu))
    A = -q / (2 * (lam + mu) + 2 * mu * a**2 / b**2)
    P = q * (lam + 2 * mu) / ((lam + mu) + mu * a**2 / b**2)
    P_fe = -model.fluid_pressure_operator @ sol.u                 # compression positive
    assert P_fe == pytest.approx(P, rel=1e-4)
    assert P_fe - q == pytest.approx(P - q, rel=0.01)

    sn = model.surface_nodes("outer")
    x, U = sn.x, sol.u[sn.dofs]
    rigid = np.zeros((len(x), 2, 3))
    rigid[:, 0, 0] = rigid[:, 1, 1] = 1.0
    rigid[:, 0, 2], rigid[:, 1, 2] = -x[:, 1], x[:, 0]
    rigid = rigid.reshape(-1, 3)
    U = U.ravel() - rigid @ np.linalg.lstsq(rigid, U.ravel(), rcond=None)[0]
    ur = np.einsum("ij,ij->i", U.reshape(-1, 2), x / np.linalg.norm(x, axis=1, keepdims=True))
    np.testing.assert_allclose(ur, A * (b - a**2 / b), rtol=5e-3)
    assert sol.residual < 1e-8


# --------------------------------------------------------------------------- cylinders
@pytest.fixture(scope="module")
def cylinders(tmp_path_factory):
    """cylinder8 with bone and solid-fluid (0.25 mm), each read, factorised and contact-ready."""
    base = tmp_path_factory.mktemp("solid_fluid")
    out = {}
    for kind in ("bone", "fluid"):
        folder = base / kind
        mesh2d.run_mesh2d(folder, mesh2d.preset_domain("cylinder8", bone=kind == "bone",
                                                       solid_fluid=kind == "fluid"), SIZE)
        model, system, region, info = open_model(folder)
        out[kind] = (folder, model, ContactModel.from_fe(model, system, region), region)
    return out


CYLINDER = "cylinder:2.38"          # a 2.38 mm diameter cylinder
DEPTH = 0.76


def test_fluid_keeps_its_volume_under_indentation(cylinders):
    """2.38 mm cylinder 0.76 mm into the solid-fluid cylinder8 (1 mm shell, 6 mm fluid core).
    The fluid's area change over the area swept under the contact (sum of tributary length x
    inward normal displacement over the nodes in contact, 0.37 mm^2) measures 2.9e-9 (3.3e-9 on
    a 0.125 mm mesh): the fluid is compressible only through its bulk modulus, FLUID_BULK_RATIO
    (1e7) times the solid's, so the ratio is (P / kappa_solid, 4e-4) x (fluid area / swept area,
    76) / FLUID_BULK_RATIO. Asserted < 1e-8 (3x margin; a FLUID_BULK_RATIO below about 4e6 would
    fail it). For scale, the same core as a solid (layer 1's modulus, nu 0.48) gives up 16 % of
    the swept area, at nu = 0.4999 9e-4."""
    _, model, cm, region = cylinders["fluid"]
    ind = make_indentor(CYLINDER)
    res = cm.indent(ind, depth_mm=DEPTH)
    assert res.kkt["ok"]
    u = cm.compliance(ind.approach).displacement(res.force_N)
    sn = model.surface_nodes(region)
    un = np.einsum("ij,ij->i", u[sn.dofs], sn.normal)
    swept = float(np.sum(sn.area[res.active] * un[res.active]))
    assert swept < -0.2                                       # pushed in: about 0.37 mm^2
    assert abs(model.fluid_volume_change(u)) / abs(swept) < 1e-8
    assert -model.fluid_pressure_operator @ u > 0             # the fluid is compressed


def _hollow(folder):
    """The solid-fluid model folder's shell alone: the same solid triangles, no fluid."""
    model, info = read_model(folder)
    cells = model.mesh.t.T[model.layer != FLUID_LAYER]
    used, cells = np.unique(cells, return_inverse=True)
    cells = cells.reshape(-1, 3)
    shell = Model(model.mesh.p.T[used], cells, np.ones(len(cells), int),
                  {k: v[used] for k, v in model.regions.items()}, material=model.material)
    return ContactModel.from_fe(shell, factorise(shell, info), "surface")


def test_solid_fluid_is_much_softer_than_the_cylinder_with_bone(cylinders):
    """Force at 0.76 mm with the 2.38 mm cylinder (m33338, nu 0.48): the bone cylinder needs
    15.3 times the solid-fluid's force (on 0.25 and on the default 0.125 mm meshes alike).
    Asserted: more than 10 times. The softness is the 1 mm shell's: the same shell
    triangles without the fluid need 5.5 % less force (both meshes); the fluid, a constraint added
    to the same shell, can only stiffen it. Asserted: between 0 and 25 % more than the shell alone
    (a solid core, layer 1's modulus, needs 13 times the solid-fluid's force)."""
    ind = make_indentor(CYLINDER)
    f_bone = cylinders["bone"][2].indent(ind, depth_mm=DEPTH).total_force_N
    f_fluid = cylinders["fluid"][2].indent(ind, depth_mm=DEPTH).total_force_N
    assert f_bone / f_fluid > 10
    f_shell = _hollow(cylinders["fluid"][0]).indent(ind, depth_mm=DEPTH).total_force_N
    assert f_shell < f_fluid < 1.25 * f_shell


# --------------------------------------------------------------------------- command line
def test_mesh_command_solid_fluid(tmp_path):
    out = tmp_path / "f"
    assert pipeline.main(["mesh", "--preset", "cylinder8", "--solid-fluid", "--size", "0.25",
                          "--out", str(out), "--quiet"]) == 0
    m = meshio.read(out / "mesh.vtu")
    layer = m.cell_data["layer"][0]
    assert set(np.unique(layer).tolist()) == {1, FLUID_LAYER}
    info = json.loads((out / "model.json").read_text())
    assert info["params"]["fluid_core_diameter_mm"] == pytest.approx(6.0)
    x = m.points[m.cells_dict["triangle"][layer == FLUID_LAYER]][..., :2]
    assert np.hypot(x[..., 0], x[..., 1]).max() < 3.0 + 1e-6      # the fluid stays inside the 1 mm shell


@pytest.mark.parametrize("flags, pattern", [
    (["--preset", "cylinder8", "--solid-fluid", "--bone"], "--bone or --solid-fluid"),
    (["--preset", "block", "--solid-fluid"], "--solid-fluid"),
])
def test_mesh_command_refuses_solid_fluid_misuse(tmp_path, flags, pattern):
    out = tmp_path / "f"
    code, _, err, _ = cli("mesh", *flags, "--size", "0.25", "--out", out, "--quiet")
    lines = err.strip().splitlines()
    assert code == 2 and len(lines) == 1 and lines[0].startswith("error: "), err
    assert pattern in lines[0] and "Traceback" not in err
    assert not any(tmp_path.iterdir())                            # nothing written


def test_preset_domain_refuses_solid_fluid_misuse():
    with pytest.raises(InputError):
        mesh2d.preset_domain("cylinder8", bone=True, solid_fluid=True)
    with pytest.raises(InputError):
        mesh2d.preset_domain("square", solid_fluid=True)


# --------------------------------------------------------------------------- rectangles
def test_block_holds_its_sides_and_square_only_its_bottom():
    block = mesh2d.preset_domain("block")
    held = block.fixed(np.array([[-20.0, -5.0], [20.0, -5.0], [0.0, -18.0], [0.0, 0.0]]))
    assert held.tolist() == [True, True, True, False]
    square = mesh2d.preset_domain("square")
    held = square.fixed(np.array([[-4.0, -2.0], [4.0, -2.0], [0.0, -8.0]]))
    assert held.tolist() == [False, False, True]


def test_held_inner_fluid_nodes_do_not_hold_the_solid():
    """The fluid's inner nodes are held only because they carry nothing: a solid-fluid model with
    no support is still refused as singular."""
    d = mesh2d.preset_domain("cylinder8", solid_fluid=True)
    pts, tri, lay = mesh2d.mesh_domain(d, mesh2d.Sizing2D(size_mm=0.5))
    model = Model(pts, tri, lay, {"outer": mesh2d.boundary_points(tri, len(pts))}, material="m3")
    with pytest.raises(InputError, match="nothing holds translation x"):
        model.solve(pressures={"outer": 0.001})
