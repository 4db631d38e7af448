"""Back end of `pipeline.py prepare`: build and store a model folder's response model
(fem.experiments.response) for a material, approach and receptor grid, so that later `indent` commands with
the same inputs and no PVD answer without factorising. Returns the summary text.

    prepare_folder("out/cyl8", material="m43338", approach="0,-1,0")
"""
from __future__ import annotations

import time

import numpy as np

from fingertip.errors import InputError
from fingertip.progress import as_progress
from fem.io.modelfolder import (
    CONDENSE_MAX_NODES,
    CONTACT_REGION,
    approach_down,
    folder_dim,
    folder_info,
    read_model,
)
from fem.experiments.scene import Receptors


def parse_approach(text, dim: int) -> np.ndarray:
    """--approach 'x,y,z' -> (3,) unit vector; a 2D model's approach lies in the x-y plane."""
    try:
        a = np.array([float(v) for v in str(text).split(",")])
        if a.shape != (3,) or not np.all(np.isfinite(a)) or not np.linalg.norm(a) > 0:
            raise ValueError
    except ValueError:
        raise InputError(f"--approach {text}: give three numbers x,y,z (e.g. 0,-1,0), not all zero") from None
    if dim == 2 and a[2] != 0:
        raise InputError(f"--approach {text}: a 2D model is indented within its x-y plane: give z = 0")
    return a / np.linalg.norm(a)


def prepare_folder(model_dir, material=None, nu=None, approach=None, receptor_depths="0.5,0.75,1.0",
                   receptor_spacing=1.0, line=None, progress=True) -> str:
    """Build (or find) the response model of a model folder for these inputs and store it in
    <model>/response/<key>/. approach: 'x,y,z' (default: the model's support, -y in 2D);
    receptor_*: as `pipeline.py indent`. Returns the summary text."""
    from fem.experiments.runner import receptor_line
    from fem.io.modelfolder import receptor_surface
    from fem.receptors.grid import receptor_grid
    from fem.experiments.response import ResponseStore, stored_responses

    t0 = time.perf_counter()
    info = folder_info(model_dir)
    dim = folder_dim(info)
    a = approach_down(info) if approach is None else parse_approach(approach, dim)
    if dim == 2:
        a = np.array([a[0], a[1], 0.0]) / np.linalg.norm(a[:2])
    receptors = {"depths_mm": receptor_depths, "spacing_mm": receptor_spacing}
    if line:
        axis, _, value = line.partition("=")
        receptors["line"] = [axis, value]
    rc = Receptors.from_dict(receptors)
    model, info = read_model(model_dir, material, nu)
    sn = model.surface_nodes(CONTACT_REGION[model.dim])
    if len(sn.nodes) > CONDENSE_MAX_NODES:
        raise InputError(f"the contact region has {len(sn.nodes)} candidates, more than the "
                         f"{CONDENSE_MAX_NODES} a response model condenses: run `pipeline.py indent` with "
                         f"your scene and --no-pvd, which stores one for the candidates it can touch")
    grid = receptor_grid(*receptor_surface(model, sn), np.asarray(rc.depths_mm, float), rc.spacing_mm,
                         receptor_line(rc.line, sn, model.dim))
    store = ResponseStore(model_dir)
    _, _, used = stored_responses(store, model, [a], grid, np.ones(len(sn.nodes), bool), as_progress(progress))
    key, how, built, size = used[0]
    return (f"response model {how} in {store.path(key)} ({time.perf_counter() - t0:.1f} s): "
            f"{len(sn.nodes)} contact candidates along {(np.round(a, 6) + 0.0).tolist()}, {len(grid.points_mm)} "
            f"receptor points, material {model.material.code}, {size / 2**20:.1f} MB, built in {built:.2f} s")
