"""The model folder of `pipeline.py mesh` (mesh.vtu + model.json) read as a held, factorised model.

    model, info = read_model("out/cyl8")                 # fem.core.model.Model, model.json dict
    system = factorise(model, info, candidates)          # held as HELD says, candidates condensed
    model, system, region, info = open_model("out/cyl8") # both, every contact candidate condensed
"""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from fem.core.materials import DEFAULT_CODE, DEFAULT_NU
from fem.core.model import Model
from fingertip.errors import InputError
from fingertip.progress import as_progress

# The proximal cut is where the distal phalanx joins the rest of the finger, which the experiments
# hold still (thesis 2.2.2: hand restrained, no joint moves; 6.2.1: the ends' boundary conditions
# differ markedly and deformation fades faster proximally). Left free, the cut swung by 12.5 % of a
# 2 mm line load on the human preset (docs/verification.md). Only its core is held (layers 3-5,
# `proximal_core`): the skin goes on proximally, so indentors as long as the finger (bars and
# wedges along the axis, steps, large cylinders) press the cut's skin instead of a fixed rim.
HELD = {3: {"nail": 0.0, "support": (None, 0.0, None), "proximal_core": 0.0}, 2: {"fixed": 0.0}}
"""Constraints of a model folder per dimension: 3D nail and the proximal cut's core fixed, support
held along its normal; 2D `fixed` held (`held_regions` skips regions a mesh lacks)."""
SKIN_LAYERS = (1, 2)
"""Epidermis and dermis: their vertices on the proximal cut are not held (`proximal_core`)."""
CONTACT_REGION = {3: "volar", 2: "surface"}
"""Contact candidate region of a model folder per dimension."""
CONDENSE_MAX_NODES = 8000
"""Largest candidate set whose dense compliance `factorise` stores (8000 nodes: 0.5 GB, k^3 flops)."""

def read_model(model_dir, material=None, nu=None):
    """(fem.core.model.Model, model.json dict) of a model folder; material and nu default to model.json's.

    A 3D model with a `proximal` cut gets the region `proximal_core`: the cut's vertices outside
    the skin layers (SKIN_LAYERS), which HELD fixes."""
    folder = Path(model_dir)
    info = folder_info(folder)
    own_material, own_nu = folder_material(info)
    model = Model.from_mesh(folder / "mesh.vtu", material=material or own_material, nu=own_nu if nu is None else nu)
    if "proximal" in model.regions and "proximal_core" not in model.regions:
        skin = np.zeros(model.mesh.nvertices, bool)
        skin[model.mesh.t[:, np.isin(model.layer, SKIN_LAYERS)].ravel()] = True
        model.regions["proximal_core"] = model.regions["proximal"] & ~skin
    return model, info


def folder_info(model_dir) -> dict:
    """model.json of a model folder ({} if it has none); InputError without mesh.vtu or for an
    unreadable model.json."""
    if not str(model_dir).strip():
        raise InputError("the model folder is empty: give the folder `pipeline.py mesh` wrote (mesh.vtu + model.json)")
    folder = Path(model_dir)
    if folder.exists() and not folder.is_dir():
        raise InputError(f"model folder '{model_dir}' is a file: give the folder `pipeline.py mesh` wrote "
                         f"(mesh.vtu + model.json)")
    if not (folder / "mesh.vtu").is_file():
        raise InputError(f"no mesh.vtu in '{model_dir}': run `pipeline.py mesh` first or give a model folder")
    if not (folder / "model.json").is_file():
        return {}
    try:
        info = json.loads((folder / "model.json").read_text())
    except (OSError, UnicodeDecodeError, ValueError) as exc:
        raise InputError(f"cannot read {folder / 'model.json'}: {exc}; re-run `pipeline.py mesh`") from None
    types = {"kind": str, "material": str, "nu": (int, float), "params": dict, "regions": dict, "domain": str}
    wrong = [k for k, t in types.items() if isinstance(info, dict) and k in info
             and (not isinstance(info[k], t) or isinstance(info[k], bool))]
    if not isinstance(info, dict) or wrong:
        raise InputError(f"{folder / 'model.json'} is not a model folder's model.json"
                         + (f" (wrong type of {', '.join(wrong)})" if wrong else "") + "; re-run `pipeline.py mesh`")
    return info


def folder_material(info: dict) -> tuple[str, float]:
    """(material code, nu) a model folder's model.json records (`folder_info`; the defaults of
    fem.core.materials when it names none)."""
    return info.get("material", DEFAULT_CODE), info.get("nu", DEFAULT_NU)


def folder_dim(info: dict) -> int:
    """Dimension of a model folder from its model.json (`folder_info`): 2 for a plane-strain mesh."""
    return 2 if str(info.get("kind", "")).startswith("2d") else 3


def held_regions(model) -> dict:
    """`HELD` for the model's dimension, restricted to the regions its mesh has (a model of
    `read_model`: a 3D proximal cut comes with its `proximal_core`)."""
    if "proximal" in model.regions and "proximal_core" not in model.regions:
        raise ValueError("the model has a proximal cut but no 'proximal_core' region: read it with read_model")
    return {k: v for k, v in HELD[model.dim].items() if k in model.regions}


def approach_down(info) -> np.ndarray:
    """(3,) default approach of a model folder: minus its support's vertical_up (-y if none)."""
    return -np.asarray(info.get("regions", {}).get("support", {}).get("vertical_up", [0.0, 1.0, 0.0]), float)


def factorise(model, info, candidates=None, progress=None):
    """LinearSystem of a model folder's model, held as `HELD` says, factorised with contact
    candidates condensed along `approach_down` when there are at most CONDENSE_MAX_NODES of them.
    candidates: P2 node ids (default: every node of the contact region), e.g. `fem.contact.linear.reach`
    of the indentations to come: fewer condensed nodes factorise faster (the Schur complement
    costs grow with their number). progress: optional `fingertip.progress` object (None: silent)
    shown the stiffness assembly and the factorisation (timed against this machine's history)."""
    progress = as_progress(progress)
    nodes = model.surface_nodes(CONTACT_REGION[model.dim]).nodes if candidates is None else candidates
    condense = (nodes, approach_down(info)) if 0 < len(nodes) <= CONDENSE_MAX_NODES else None
    with progress.task(f"assembling the stiffness of {model.ndof} DOFs", kind=f"assemble-{model.dim}d",
                       size=model.ndof):
        model.K_dev
    what = f"factorising {model.ndof} DOFs" + (f" with {len(nodes)} contact candidates condensed" if condense else "")
    size = model.ndof + (3 * len(nodes) if condense else 0)     # the Schur block adds to the cost
    with progress.task(what, kind=f"factorise-{model.dim}d", size=size):
        return model.system(held_regions(model), condense=condense)


def open_model(model_dir, material=None, nu=None, progress=None):
    """(fem.core.model.Model, LinearSystem, contact region name, model.json dict) of a model folder,
    factorised with every contact candidate condensed (`factorise`; progress as there)."""
    model, info = read_model(model_dir, material, nu)
    return model, factorise(model, info, progress=progress), CONTACT_REGION[model.dim], info


def receptor_surface(model, sn) -> tuple[np.ndarray, np.ndarray]:
    """(positions (k, dim) mm, outward normals (k, dim)) of the contact-region nodes `sn` that may
    carry receptor sites (`pad_nodes`)."""
    keep = pad_nodes(model, sn)
    return sn.x[keep], sn.normal[keep]


def pad_nodes(model, sn) -> np.ndarray:
    """(n,) bool: the contact-region nodes `sn` that may carry receptor sites: all but those on a
    3D end cut. Below a node on the rim of a cut the receptors lie on the cut plane, which the mesh
    reproduces only within pytetwild's envelope (0.02 mm): with a 0.05 mm envelope one fell
    outside the mesh."""
    ends = [model.region_nodes(r) for r in ("proximal", "distal") if r in model.regions]
    return ~np.isin(sn.nodes, np.concatenate(ends)) if ends else np.ones(len(sn.nodes), bool)
