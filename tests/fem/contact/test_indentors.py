"""Geometry of the rigid indentors: standoff (gap along the approach), normals, placement, codes."""
import math

import numpy as np
import pytest

from fem.contact import indentors as ind
from fingertip.errors import InputError

RNG = np.random.default_rng(3)


def _surface_point(indentor, u, v, part=0):
    """World point on the indentor surface at local (u, v) when its tip is at the origin."""
    du, dv = indentor.offsets_mm[part]
    h = indentor.parts[part].height(np.array([u - du]), np.array([v - dv]))[0][0]
    return indentor.origin_mm + u * indentor.e1 + v * indentor.e2 - h * indentor.approach


def test_catalogue_numbers():
    assert ind.shapes_for("C5")[1][0].diameter_mm == 9.52
    assert ind.shapes_for("cylinder:C8")[1][0].diameter_mm == 25.4
    assert ind.shapes_for("cylinder:2.3805")[1][0].diameter_mm == 2.3805
    assert ind.shapes_for("R2")[1][0].width_mm == 38.1
    assert [ind.shapes_for(f"step:{i}")[1][0].half_wavelength_mm for i in range(6)] == \
        [0.0, 0.45, 1.195, 1.23, 3.038, 3.134]
    cone = ind.shapes_for("cone")[1][0]
    assert (cone.base_radius_mm, cone.height_mm) == (3.175, 2.4)
    assert ind.shapes_for("punch")[1][0].diameter_mm == 6.35
    plate = ind.shapes_for("plate")[1][0]
    assert (plate.width_mm, plate.length_mm) == (20.0, 20.0)
    assert ind.shapes_for("grating:0.5:1,2")[1][0].gaps_mm == (1.0, 2.0)
    assert ind.shapes_for("ellipsoid:3,2,1")[1][0].semi_w_mm == 1.0


@pytest.mark.parametrize("spec", ["C9", "step:6", "step:a", "cylinder:-1", "bar:x", "sphere",
                                  "ellipsoid:1,2", "wedge:95", "blob", "grating:0.5:1,-2"])
def test_bad_codes_raise_input_error(spec):
    with pytest.raises(InputError):
        ind.shapes_for(spec)


@pytest.mark.parametrize("spec", ["C5", "sphere:5", "ellipsoid:3,2,1.5", "cone", "wedge:20",
                                  "step:3", "cylinder:3.18", "two-point:3"])
@pytest.mark.parametrize("orientation", ["parallel", "perpendicular", 33.0])
@pytest.mark.parametrize("incline", [0.0, 30.0])
def test_normal_is_gradient_of_standoff(spec, orientation, incline):
    """The outward normal equals the normalised gradient of the standoff wherever it is smooth."""
    indentor = ind.make_indentor(spec, orientation=orientation, incline_deg=incline,
                                 position_mm=(0.4, -1.0))
    # random points near the indentor surface, away from kinks (wedge edge, cone tip, step ends)
    pts = []
    while len(pts) < 20:
        u, v = RNG.uniform(-1.2, 1.2, 2)
        p = _surface_point(indentor, u, v, part=0) + RNG.uniform(-0.3, 0.3) * indentor.approach
        if np.all(np.isfinite(p)) and abs(v) > 0.05 and np.hypot(u, v) > 0.05:
            if spec.startswith("step") and min(abs(v), abs(v - 1.23)) < 0.05:
                continue
            pts.append(p)
    pts = np.array(pts)
    eps = 1e-6
    grad = np.column_stack([(indentor.standoff(pts + eps * e) - indentor.standoff(pts - eps * e)) / (2 * eps)
                            for e in np.eye(3)])
    ok = np.all(np.isfinite(grad), axis=1)
    assert ok.sum() >= 15
    expect = grad[ok] / np.linalg.norm(grad[ok], axis=1, keepdims=True)
    np.testing.assert_allclose(indentor.normal(pts[ok]), expect, atol=1e-5)


def test_sphere_gap_and_normal_are_exact():
    r = 5.0
    s = ind.make_indentor(f"sphere:{r}", position_mm=(1.0, 2.0))
    centre = s.origin_mm - r * s.approach          # tip at origin, centre behind it
    d = RNG.normal(size=(50, 3))
    d[:, 1] = np.abs(d[:, 1]) + 0.5                  # the lower cap, facing the approach (-y)
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    surf = centre - r * d
    np.testing.assert_allclose(s.standoff(surf), 0.0, atol=1e-10)
    np.testing.assert_allclose(s.normal(surf), -d, atol=1e-10)
    # a point 0.3 mm below the surface along -y: gap 0.3 mm; after 0.5 mm travel: -0.2 mm
    below = surf + 0.3 * s.approach
    np.testing.assert_allclose(s.gap(below, travel_mm=0.5), -0.2, atol=1e-10)


def test_cylinder_orientation_and_incline():
    perp = ind.make_indentor("C5", orientation="perpendicular")
    par = ind.make_indentor("C5", orientation="parallel")
    np.testing.assert_allclose(np.abs(perp.e1), [1, 0, 0], atol=1e-12)
    np.testing.assert_allclose(par.e1, [0, 0, 1], atol=1e-12)
    np.testing.assert_allclose(par.e2, [1, 0, 0], atol=1e-12)
    np.testing.assert_allclose(perp.e2, [0, 0, 1], atol=1e-12)
    r = 9.52 / 2
    # perpendicular cylinder: the gap varies along z, not along x
    p = np.array([[5.0, 0.0, 1.0], [-7.0, 0.0, 1.0]])
    np.testing.assert_allclose(perp.standoff(p), r - math.sqrt(r * r - 1.0), atol=1e-12)
    np.testing.assert_allclose(par.standoff(p[:1]), np.inf)
    tilted = ind.make_indentor("C5", orientation=45.0)
    assert math.isclose(abs(tilted.e1 @ [0, 0, 1]), math.cos(math.radians(45)), abs_tol=1e-12)
    inc = ind.make_indentor("C5", orientation="perpendicular", incline_deg=30.0)
    np.testing.assert_allclose(inc.approach, [0, -math.cos(math.pi / 6), 0.5], atol=1e-12)
    assert abs(inc.e1 @ inc.approach) < 1e-12 and abs(inc.e2 @ inc.approach) < 1e-12
    np.testing.assert_allclose(np.abs(inc.e1), [1, 0, 0], atol=1e-12)


def test_step_profile():
    for i, lam in enumerate(ind.STEP_HALF_WAVELENGTH_MM):
        st = ind.make_indentor(f"step:{i}")                     # across axis e2 = +x
        x = np.array([-1.0, 0.5 * lam, lam + 1e-9, lam + 2.0])
        h = st.standoff(np.column_stack([x, np.zeros(4)]))         # 2D points at y = 0
        expect = [0.0, 0.25 if lam > 0 else 0.0, 0.5, 0.5]
        np.testing.assert_allclose(h, expect, atol=1e-9)


def test_grating_bars_and_gaps():
    g = ind.make_indentor("grating:0.5:1,2")                    # bars [0,.5], [1.5,2], [4,4.5]
    x = np.array([0.25, 1.0, 1.75, 3.0, 4.25, 5.0, -0.1])
    h = g.standoff(np.column_stack([x, np.zeros_like(x)]))
    np.testing.assert_array_equal(h, [0, np.inf, 0, np.inf, 0, np.inf, np.inf])
    np.testing.assert_allclose(g.parts[0].bar_edges_mm(), [[0, 0.5], [1.5, 2], [4, 4.5]])


def test_flat_shapes_and_cone():
    pts = np.array([[0.0, 0.0, 0.0], [3.0, 0.0, 0.0], [9.0, 0.0, 9.0], [11.0, 0.0, 0.0]])
    np.testing.assert_allclose(ind.make_indentor("punch").standoff(pts), [0, 0, np.inf, np.inf])
    np.testing.assert_allclose(ind.make_indentor("plate").standoff(pts), [0, 0, 0, np.inf])
    np.testing.assert_allclose(ind.make_indentor("bar:1.5").standoff(pts[:2]), [0, np.inf])
    cone = ind.make_indentor("cone").standoff(pts)
    np.testing.assert_allclose(cone, [0, 3.0 * 2.4 / 3.175, np.inf, np.inf])
    wedge = ind.make_indentor("wedge:45").standoff(pts)
    np.testing.assert_allclose(wedge, [0, 3.0, 9.0, 11.0])


def test_two_point_is_min_of_two_tips():
    tp = ind.make_indentor("two-point:4", position_mm=(1.0, 0.0))
    x = np.array([-1.0, 1.0, 3.0])
    h = tp.standoff(np.column_stack([x, np.zeros(3), np.zeros(3)]))
    np.testing.assert_allclose(h, [0.0, 2.0 * 2.4 / 3.175, 0.0], atol=1e-12)
    assert ind.make_indentor("two-point:0").n_parts == 1
    moved = tp.shifted([0.5, 0, 0])
    np.testing.assert_allclose(moved.standoff([[-0.5, 0, 0]]), 0.0, atol=1e-12)


def test_bad_placement():
    with pytest.raises(InputError):
        ind.make_indentor("C5", orientation="sideways")
    with pytest.raises(InputError):
        ind.make_indentor("C5", approach=(0, 0, 1))
    with pytest.raises(InputError):
        ind.make_indentor("C5", position_mm=(1, 2, 3, 4))
    with pytest.raises(InputError):
        ind.make_indentor("C5").standoff(np.zeros((3, 4)))
