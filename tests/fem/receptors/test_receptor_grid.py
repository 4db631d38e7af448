"""Receptor grid placement: cells centred on x = 0 (the pad's midline), stable site ids."""
import numpy as np
import pytest

from fem.receptors.grid import receptor_grid


def arc(x):
    """Points (n, 2) and outward normals on a circle of radius 4 mm centred at the origin."""
    y = np.sqrt(16.0 - x ** 2)
    p = np.column_stack([x, y])
    return p, p / 4.0


def test_2d_sites_sit_on_the_midline_and_every_spacing():
    x = np.arange(-1.9, 1.9, 0.07) + 0.013             # no node on x = 0; y within one 1 mm cell
    p, n = arc(x)
    g = receptor_grid(p, n, depths_mm=(0.5, 1.0), spacing_mm=1.0)
    xs = np.sort(g.sites_mm[:, 0])
    np.testing.assert_array_equal(np.round(xs), [-2, -1, 0, 1, 2])      # one site per 1 mm cell
    assert np.abs(xs[1:4] - [-1, 0, 1]).max() <= 0.035  # the node nearest each cell centre


def test_3d_pad_grid_and_line_have_a_row_on_x_0():
    gx, gz = np.meshgrid(np.arange(-4.0, 4.0, 0.23) + 0.05, np.arange(0.0, 6.0, 0.23))
    p = np.column_stack([gx.ravel(), np.zeros(gx.size), gz.ravel()])
    n = np.tile([0.0, 1.0, 0.0], (len(p), 1))
    g = receptor_grid(p, n, depths_mm=(0.75,), spacing_mm=1.0)
    row = np.abs(g.sites_mm[:, 0]) <= 0.115            # half the node step
    assert len(np.unique(np.round(g.sites_mm[row, 2]))) == 7              # a whole row, z = 0..6
    line = receptor_grid(p, n, depths_mm=(0.75,), spacing_mm=0.5, line=(2, 3.0))
    assert np.all(line.sites_mm[:, 2] == 3.0) and np.abs(line.sites_mm[:, 0]).min() <= 0.115


def test_site_ids_index_the_surface_sites_at_every_depth():
    p, n = arc(np.linspace(-3, 3, 301))
    depths = (0.5, 0.75, 1.0)
    g = receptor_grid(p, n, depths_mm=depths, spacing_mm=0.5)
    k = len(g.sites_mm)
    for d in depths:
        sel = g.depth_mm == d
        assert sorted(g.site[sel]) == list(range(k))
        r = np.linalg.norm(g.points_mm[sel], axis=1)
        assert r == pytest.approx(4.0 - d, abs=1e-12)                      # along the normal
        np.testing.assert_allclose(g.points_mm[sel], g.sites_mm[g.site[sel]] * (4.0 - d) / 4.0, atol=1e-12)
