"""Receptors on a layer interface are sampled in the deeper layer, consistently.

The default 0.5 mm receptor depth equals the epidermis thickness, and tetrahedral meshes place
interfaces only to about 0.02 mm: without a rule, neighbouring receptors would fall on either side
and their strains would jump by the layers' modulus ratio.
"""
import numpy as np

from fem.core.model import Model
from fem.receptors.grid import INTERFACE_SNAP_MM, ReceptorSampler, receptor_grid
from fem.verify.closed_forms import box


def _two_layer_block(wiggle_mm):
    """2D block 4 x 3 mm, top at y = 0, a stiff 0.5 mm top layer (1) on a 10x softer layer (2);
    the mesh interface moves up and down by wiggle_mm from node to node."""
    ys = np.concatenate([np.linspace(-3.0, -0.5, 11), np.linspace(-0.5, 0.0, 5)[1:]])
    pts, tri, regions = box(np.linspace(-2.0, 2.0, 41), np.unique(ys))
    on = np.isclose(pts[:, 1], -0.5)
    pts[on, 1] += wiggle_mm * np.where(np.arange(on.sum()) % 2 == 0, 1.0, -1.0)
    layer = np.where(pts[tri].mean(axis=1)[:, 1] > -0.5, 1, 2)
    # layers from the element centroids: the top layer is what lies above the wiggling interface
    return Model(pts, tri, layer, regions, material=[1e-2, 1e-3], nu=0.3)


def test_interface_receptors_take_the_deeper_layer():
    model = _two_layer_block(0.01)
    top = np.column_stack([np.linspace(-1.0, 1.0, 21), np.zeros(21)])       # every mesh node
    grid = receptor_grid(top, np.tile([0.0, 1.0], (21, 1)), depths_mm=(0.5, 0.25, 1.0), spacing_mm=0.1)
    sampler = ReceptorSampler(model, grid)
    sol = model.solve(prescribed={"ymin": 0.0, "ymax": (None, -0.1)})
    eyy = sampler.measures(sampler.operator @ sol.u, ["strain_yy"])["strain_yy"]
    at = {d: eyy[grid.depth_mm == d] for d in (0.25, 0.5, 1.0)}
    # two layers in series under compression: the soft layer strains ~10x more than the stiff one;
    # near the wiggling interface the soft-layer strain varies by ~15 %, a stiff-layer sample
    # would be ~10x smaller
    assert np.abs(at[0.5]).min() > 0.7 * np.abs(at[1.0]).min()       # every 0.5 mm receptor in layer 2
    assert np.abs(at[0.25]).max() < 0.3 * np.abs(at[1.0]).min()      # layer 1, untouched by the rule
    shift = sampler.shift_mm[grid.depth_mm == 0.5]
    assert (shift <= INTERFACE_SNAP_MM + 1e-12).all() and shift.max() > 0   # some were moved
    assert not sampler.shift_mm[grid.depth_mm != 0.5].any()
    # control: sampled where they were placed, some 0.5 mm receptors fall in the stiff layer
    raw = (model.strain_operator(grid.points_mm[grid.depth_mm == 0.5]) @ sol.u).reshape(-1, 3)[:, 1]
    assert np.abs(raw).min() < 0.3 * np.abs(at[1.0]).min()
