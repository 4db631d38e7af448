"""The model folder of `pipeline.py mesh` (mesh.vtu + model.json) read as a held, factorised model.

    model, info = read_model("out/cyl8")                 # fem.core.model.Model, model.json dict
    system = factorise(model, info, candidates)          # held as HELD says, candidates condensed
    model, system, region, info = open_model("out/cyl8") # both, every contact candidate condensed
"""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from fem.core.discretisation import Discretisation
from fem.core.materials import DEFAULT_CODE, DEFAULT_NU, RECORDED_CODES, Material, default_code, solid_layers
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
    """(fem.core.model.Model, model.json dict) of a model folder; material and nu default to model.json's
    (`folder_material` of the mesh's layers). InputError, before anything is assembled, for a
    material that does not fit the mesh's layers (`fem.core.materials.Material.check_layers`).

    A 3D model with a `proximal` cut gets the region `proximal_core`: the cut's vertices outside
    the skin layers (SKIN_LAYERS), which HELD fixes."""
    folder = Path(model_dir)
    info = folder_info(folder)
    disc = Discretisation.from_mesh(folder / "mesh.vtu")
    own_material, own_nu = folder_material(info, disc.layer)
    if not material:
        try:
            Material(own_material).check_layers(disc.layer)
        except InputError as exc:
            raise InputError(f"{folder / 'model.json'} records a material that does not fit its mesh ({exc}): give "
                             f"a material or re-run `pipeline.py mesh`") from None
    model = Model.on(disc, material=material or own_material, nu=own_nu if nu is None else nu)
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


def folder_material(info: dict, layers=None) -> tuple[str, float]:
    """(material code, nu) of a model folder from its model.json (`folder_info`): the code it
    records, fitted to the model's layers (ids or the mesh's (M,) layer array; default: those
    model.json lists, `folder_layers`): where it names no material, or one of RECORDED_CODES that
    does not fit them (a one-layer 2D model recorded "m33338"), `fem.core.materials.default_code`
    of the layers ("m3"). nu defaults to fem.core.materials.DEFAULT_NU."""
    layers = folder_layers(info) if layers is None else solid_layers(layers)
    code = info.get("material")
    if layers and (code is None or (code in RECORDED_CODES and not fits(code, layers))):
        code = default_code(layers)
    return code or DEFAULT_CODE, info.get("nu", DEFAULT_NU)


def fits(material, layers) -> bool:
    """Whether a material (code, moduli or `Material`) fits a model with these layer ids
    (`fem.core.materials.Material.check_layers`)."""
    try:
        Material(material).check_layers(layers)
    except InputError:
        return False
    return True


def folder_layers(info: dict) -> list[int]:
    """The solid layer ids model.json lists (`layers`: a list in 2D, {id: tissue} in 3D); [] when it
    lists none (the mesh knows: `read_model`)."""
    listed = info.get("layers")
    try:
        return solid_layers(listed.keys() if isinstance(listed, dict) else listed or [])
    except (TypeError, ValueError):
        return []


def check_folder_material(model_dir, material=None, nu=None) -> None:
    """InputError when a material (a scene's, None: the folder's own) does not fit the layers the
    model folder's model.json lists: the check `read_model` makes on the mesh, made before any
    work (the mesh is not read; a model.json that lists no layers is checked when it is)."""
    info = folder_info(model_dir)
    layers = folder_layers(info)
    if layers and material is not None:
        Material(material, DEFAULT_NU if nu is None else nu).check_layers(layers)


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
