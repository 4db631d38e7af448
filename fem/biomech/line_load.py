"""The line load of thesis 6.2.1 with linear and large-deformation kinematics: the surface nodes
under a wedge pushed into a model folder's model, the deflection profiles and forces of both, and
where the two part (`compare_line_load`; `pipeline.py line-load`).

    c = compare_line_load("out/msec", depths_mm=[0.5, 1.0, 2.0])
    c.force_linear_N, c.force_nonlinear_N, c.max_difference
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fem.core.model import Model
from fem.core.neohookean import NeoHookean
from fem.io.modelfolder import CONTACT_REGION, held_regions, read_model
from fingertip.errors import InputError
from fingertip.progress import as_progress


@dataclass
class LineLoadComparison:
    """Linear and large-deformation solutions of a model whose surface nodes under the load (see
    `line_load_model`) are pushed down (approach -y) by each depth: held sideways (they move with
    the wedge) unless slip.

    Per depth (k,): force_linear_N / force_nonlinear_N [N; N/mm in 2D]; profile nodes' undeformed
    signed distance_mm (n,) from the load line (2D: x - x0; 3D: z - z0 along the finger axis,
    nodes within band_mm of x = x0) and deflection (k, n) [mm, into the body +]; max_difference
    (k,) = max |nonlinear - linear| deflection / depth; min_J (k,) smallest volume ratio reached;
    newton: residual histories of the load step ending at each depth; seconds (k,) wall time of the
    nonlinear solve up to each depth; failed: {depth: message} where the nonlinear solve could not reach the depth; dim:
    the model's space dimension (2: forces per mm of thickness)."""
    depths_mm: np.ndarray
    distance_mm: np.ndarray
    deflection_linear_mm: np.ndarray
    deflection_nonlinear_mm: np.ndarray
    force_linear_N: np.ndarray
    force_nonlinear_N: np.ndarray
    max_difference: np.ndarray
    min_J: np.ndarray
    newton: list
    seconds: np.ndarray
    failed: dict
    dim: int


def line_load_model(model_dir, material=None, nu=None, position_mm=None, half_width_mm: float = 0.0,
                    half_length_mm: float = 1.0):
    """(fem.core.model.Model with a 'load' region, load position (x0, z0) [mm]) of a model folder.

    2D: the surface vertices within half_width_mm of x = x0 (default the section's centroid x;
    at least the nearest vertex). 3D: a wedge across the finger axis (thesis 6.2.1): the volar
    vertices within half_width_mm of z = z0 (default the middle of the volar z range) and within
    half_length_mm of x = x0 (default 0), at least the nearest vertex."""
    t, info = read_model(model_dir, material, nu)
    sn = t.surface_nodes(CONTACT_REGION[t.dim])
    verts = sn.nodes[sn.nodes < t.mesh.nvertices]
    x = t.mesh.p[:, verts]
    if t.dim == 2:
        x0 = info.get("params", {}).get("centroid_mm", [0.0])[0] if position_mm is None else float(position_mm[0])
        pos = (x0, 0.0)
        inside, score = np.abs(x[0] - x0) <= half_width_mm, np.abs(x[0] - x0)
    else:
        pos = (0.0, 0.5 * (x[2].min() + x[2].max())) if position_mm is None else tuple(map(float, position_mm))
        inside = (np.abs(x[2] - pos[1]) <= half_width_mm) & (np.abs(x[0] - pos[0]) <= half_length_mm)
        score = np.hypot(x[0] - pos[0], x[2] - pos[1])
    load = verts[inside] if inside.any() else verts[[np.argmin(score)]]
    model = Model(t.mesh.p.T, t.mesh.t.T, t.layer, {**t.regions, "load": load}, material=t.material)
    return model, pos


def compare_line_load(model_dir, depths_mm=(0.05, 0.5, 1.0), material=None, nu=None, half_width_mm=0.0,
                      step_mm: float = 0.1, position_mm=None, slip: bool = False, half_length_mm: float = 1.0,
                      band_mm: float = 0.25, large_deformation: bool = True,
                      progress=None) -> LineLoadComparison:
    """Linear vs large-deformation surface deflection and force under a prescribed line load. The
    nonlinear solve goes once to the deepest depth in load steps of about step_mm, landing on every
    depth (hyperelastic: the path does not matter); large_deformation=False: the linear solution
    only, the nonlinear fields NaN. progress: optional `fingertip.progress` object (None: silent)
    shown the linear factorisation and each load step."""
    depths = np.asarray(depths_mm, float).ravel()
    if not depths.size or np.any(depths <= 0) or not step_mm > 0 or half_width_mm < 0 or half_length_mm < 0:
        raise InputError(f"line load: depths ({depths.tolist()}) and step ({step_mm}) must be > 0 mm, "
                         f"half width ({half_width_mm}) and half length ({half_length_mm}) >= 0 mm")
    model, pos = line_load_model(model_dir, material, nu, position_mm, half_width_mm, half_length_mm)
    d = model.dim
    sn = model.surface_nodes(CONTACT_REGION[d])
    if d == 2:
        along = sn.x[:, 0] - pos[0]
        on = np.ones(len(along), bool)
    else:
        along = sn.x[:, 2] - pos[1]
        on = np.abs(sn.x[:, 0] - pos[0]) <= band_mm
    order = np.flatnonzero(on)[np.argsort(along[on])]
    ydofs = sn.dofs[order, 1]
    load = model.node_dofs(model.region_nodes("load"))[:, 1]
    deepest = float(depths.max())
    push = [None if slip else 0.0] * d
    push[1] = -deepest
    pres = {**held_regions(model), "load": tuple(push)}
    with as_progress(progress).task(f"linear solve of {model.ndof} DOFs", kind=f"factorise-{d}d", size=model.ndof):
        unit = model.system(pres).u0 / deepest                     # linear: proportional to the depth
    lin = depths[:, None] * -unit[ydofs]
    f_lin = depths * -float((model.K @ unit)[load].sum())
    n = len(depths)
    non, f_non, J, secs = np.full((n, len(ydofs)), np.nan), np.full(n, np.nan), np.full(n, np.nan), np.zeros(n)
    newton, failed = [[] for _ in range(n)], {}
    if large_deformation:
        res = NeoHookean(model).solve(pres, steps=max(1, int(np.ceil(deepest / step_mm - 1e-9))),
                                      stops=depths / deepest, partial=True, progress=progress)
        for k, depth in enumerate(depths):
            hit = np.flatnonzero(np.abs(res.t * deepest - depth) < 1e-9 * deepest)
            if not hit.size:
                failed[float(depth)] = res.stopped
                continue
            i = hit[0]
            non[k], f_non[k] = -res.u[i][ydofs], -float(res.reaction[i][load].sum())
            J[k], secs[k], newton[k] = res.min_J[:i + 1].min(), res.seconds[i], res.history[i]
    diff = np.abs(non - lin).max(axis=1) / depths
    return LineLoadComparison(depths, along[order], lin, non, f_lin, f_non, diff, J, newton, secs, failed, d)
