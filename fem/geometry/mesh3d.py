"""Conforming tetrahedral mesh of the layered model: pytetwild, layer labels, regions, checks, cache.

All layer shells go into pytetwild as one triangle soup (each face once), so tetrahedra conform to
every interface. pytetwild returns no labels, and with nested shells its own outside filter kept
a slab of tets about one edge length beyond the flat end caps; so its background is kept
(`disable_filtering`) and each tet is labelled by the number of shells whose winding number at its
centroid exceeds 0.5 (0 = outside, dropped). Its surface simplification is skipped (the input is
already clean, and it is a large share of the meshing time). A background sizing
field (pytetwild's `bg_*` arguments) asks for `size_mm` in the top `fine_depth_mm` of the volar
skin, growing by `growth` mm per mm of distance from that zone up to `coarse_mm`.
pytetwild runs in a worker process made reproducible (`fem.geometry.tetwild`): the same inputs give
the same mesh; meshes are also cached by a hash of all inputs, so a second run reads its first's.
"""
from __future__ import annotations

import hashlib
import json
import time
from dataclasses import asdict, dataclass
from importlib import metadata
from pathlib import Path

import igl
import meshio
import numpy as np

from fem.geometry.layered import N_LAYERS, LayeredModel, check_positive
from fem.geometry.tetwild import fixed_seed_library, run_tetwild
from fingertip.declare import declared, positive
from fingertip.errors import InputError
from fingertip.progress import as_progress, cache_root
from fingertip.staging import atomic_write, staged_output, write_json

#: bump when tetrahedralize() changes, so cached meshes are not reused (2: pytetwild reproducible,
#: one thread and a fixed seed; 3: the surfaces resampled on rays for the size, `surface_model`)
MESHER_VERSION = 3
PROPORTIONAL = {"coarse_mm": (6.0, 3.0), "growth": (1.0, 1.0), "epsilon_mm": (0.04, 0.02)}
"""3D sizes that follow size_mm when not given (`in_proportion`): {field: (per mm of size_mm, at
most)}: coarse_mm 6 size_mm, at most 3 mm; growth size_mm per mm, at most 1; pytetwild's envelope
0.04 size_mm, at most 0.02 mm (the defaults 3, 0.5 and 0.02 mm at the default 0.5 mm; a wider
envelope lets tets straddle the layer interfaces)."""
SURFACE_FACET = 0.5
"""Longest facet of the model surfaces a mesh is built from, as a fraction of size_mm (`surface_model`)."""


def in_proportion(sizing, rules: dict) -> None:
    """Fill the fields of a sizing not given (None) in proportion to its size_mm, so that a smaller
    size refines every layer alike: rules {field: (ratio, at most)} gives field = min(ratio
    size_mm, at most), the bound being what the fingertip models need (a coarser element, a faster
    growth, a looser envelope only spoil the mesh). Called from the sizings' __post_init__ (frozen
    dataclasses), so an instance holds the sizes it meshes with."""
    size = sizing.size_mm
    if not isinstance(size, (int, float)):
        return
    for name, (ratio, most) in rules.items():
        if getattr(sizing, name) is None:
            object.__setattr__(sizing, name, float(f"{min(ratio * size, most):.12g}"))


@dataclass(frozen=True)
class Sizing:
    """Target edge lengths (mm) and mesher settings.

    size_mm: on the volar skin (top fine_depth_mm, volar_span_deg of the model, fine_z_frac of the
    length); grows by `growth` mm per mm away from it, capped at coarse_mm. epsilon_mm: pytetwild
    envelope (max distance of the meshed interfaces from the model surfaces). coarse_mm, growth and
    epsilon_mm follow size_mm unless given (PROPORTIONAL). opt_iter: pytetwild optimisation passes.
    """
    size_mm: float = declared(0.5, "mm", "target edge length on the volar skin (3D) or top surface (2D)", text=positive)
    coarse_mm: float | None = declared(None, "mm", "largest edge length", text=positive,
                                       default_text="6 x size, at most 3")
    growth: float | None = declared(None, "mm per mm", "edge length growth per mm away from the fine zone",
                                    text=positive, default_text="size per mm, at most 1")
    fine_depth_mm: float = declared(1.5, "mm", "depth of the fine zone below the volar (3D) or top (2D) surface", text=positive)
    fine_z_frac: tuple = (0.0, 1.0)
    epsilon_mm: float | None = None
    opt_iter: int = 20

    def __post_init__(self):
        in_proportion(self, PROPORTIONAL)

    def check(self) -> None:
        check_sizes(self, 0.1)
        check_positive(self, "epsilon_mm")
        lo, hi = self.fine_z_frac
        if not 0 <= lo < hi <= 1:
            raise InputError(f"fine_z_frac must be two fractions 0 <= lo < hi <= 1; got {lo} {hi}")
        if self.opt_iter < 1:
            raise InputError(f"opt_iter must be >= 1; got {self.opt_iter}")


def check_sizes(sizing, min_size_mm: float, kind: str = "3D") -> None:
    """Raise InputError unless the sizing's lengths are positive and min_size_mm <= size <= coarse;
    kind ("3D", "2D") names the models whose default a message compares with."""
    check_positive(sizing, "size_mm", "coarse_mm", "growth", "fine_depth_mm")
    if sizing.size_mm < min_size_mm:
        raise InputError(f"size_mm {sizing.size_mm:g} mm is below {min_size_mm:g} mm, too many elements for this "
                         f"machine: give size_mm of at least {min_size_mm:g}")
    if sizing.coarse_mm < sizing.size_mm:
        default = sizing.coarse_mm == type(sizing)().coarse_mm
        raise InputError(f"size_mm {sizing.size_mm:g} mm is larger than coarse_mm {sizing.coarse_mm:g} mm"
                         + (f" (the default of {kind} models)" if default else "")
                         + "; give coarse_mm at least as large as size_mm")


@dataclass
class TetMesh:
    """points (P, 3) mm; tets (T, 4) positive orientation; layer (T,) int32 1..5;
    tags: region name -> (P,) uint8 flags on boundary vertices."""
    points: np.ndarray
    tets: np.ndarray
    layer: np.ndarray
    tags: dict

    def to_meshio(self):

        return meshio.Mesh(self.points, [("tetra", self.tets.astype(np.int64))],
                           cell_data={"layer": [self.layer.astype(np.int32)]},
                           point_data={k: v.astype(np.uint8) for k, v in self.tags.items()})


# ---------------------------------------------------------------------- sizing
def surface_model(model: LayeredModel, sizing: Sizing) -> LayeredModel:
    """The model on as many rays as its mesh needs: no facet of the outer surface longer than
    SURFACE_FACET size_mm (`LayeredModel.rays_for`), so the mesh's surface, not the model's
    polygons, sets the resolution. The same model for every function here that takes a model and a
    sizing (resampling an already resampled model returns it)."""
    return model.resampled(model.rays_for(SURFACE_FACET * sizing.size_mm))


def angle_from(theta: np.ndarray, centre: float) -> np.ndarray:
    """Absolute angular distance (rad, 0..pi) of theta from the direction `centre` (rad)."""
    return np.abs(np.angle(np.exp(1j * (theta - centre))))


def sizing_values(model: LayeredModel, sizing: Sizing, points: np.ndarray) -> np.ndarray:
    """Target edge length (mm) at (M, 3) points."""
    theta, r, R = model.polar(points)
    depth = np.clip(R - r, 0.0, None)
    half_span = np.deg2rad(model.params.volar_span_deg) / 2
    off_angle = np.clip(angle_from(theta, np.pi / 2) - half_span, 0.0, None) * r
    zf = model.z_frac(points[:, 2])
    lo, hi = sizing.fine_z_frac
    L = model.z_mm[-1] - model.z_mm[0]
    off_z = (np.clip(lo - zf, 0, None) + np.clip(zf - hi, 0, None)) * L
    dist = np.sqrt(np.clip(depth - sizing.fine_depth_mm, 0, None) ** 2 + off_angle**2 + off_z**2)
    return np.minimum(sizing.size_mm + sizing.growth * dist, sizing.coarse_mm)


BACKGROUND_SPACING_MM = 0.75
"""Grid step of the background sizing mesh."""

def background_mesh(model: LayeredModel, sizing: Sizing, spacing_mm: float = BACKGROUND_SPACING_MM):
    """Regular tetrahedral grid over the model's bounding box with the target sizes at its points:
    (points (n, 3), tets (m, 4) int32, values (n,))."""
    import pyvista as pv  # 0.17 s of import, which a mesh from the cache does without

    v = model.vertices()
    lo, hi = v.min(0) - spacing_mm, v.max(0) + spacing_mm
    dims = np.ceil((hi - lo) / spacing_mm).astype(int) + 1
    grid = pv.ImageData(dimensions=dims, spacing=(spacing_mm,) * 3, origin=lo).to_tetrahedra()
    pts = np.asarray(grid.points, float)
    return pts, grid.cells_dict[10].astype(np.int32), sizing_values(model, sizing, pts)


# ---------------------------------------------------------------------- meshing
def expected_tets(bg_t, bg_v) -> float:
    """Rough tet count pytetwild makes for a background mesh of regular tets `bg_t` with target
    edge lengths `bg_v` [mm] at their points: sum of each tet's volume over that of a regular tet
    of its size; a size measure for the meshing-time estimate (outside tets included)."""
    return float(np.sum(6 * np.sqrt(2) / np.mean(bg_v[bg_t], axis=1) ** 3)) * BACKGROUND_SPACING_MM ** 3 / 5


def tetrahedralize(model: LayeredModel, sizing: Sizing):
    """Run pytetwild on the merged shells -> (points (P, 3), tets (T, 4)) of the tets inside the
    outer shell, unused points removed."""
    sizing.check()
    model = surface_model(model, sizing)
    v, f = model.vertices(), model.faces().astype(np.int32)
    diag = float(np.linalg.norm(v.max(0) - v.min(0)))
    bg_p, bg_t, bg_v = background_mesh(model, sizing)
    pts, tets = run_tetwild({
        "vertices": v, "faces": f, "edge_length_abs": sizing.coarse_mm, "epsilon": sizing.epsilon_mm / diag,
        "vtk_ordering": True, "quiet": True, "simplify": False, "disable_filtering": True,
        "num_opt_iter": sizing.opt_iter, "bg_vertices": bg_p, "bg_tets": bg_t, "bg_values": bg_v})
    keep = label_tets(model, pts, tets) > 0
    tets = tets[keep]
    used, tets = np.unique(tets, return_inverse=True)
    return pts[used], tets.reshape(-1, 4).astype(np.int64)


def label_tets(model: LayeredModel, points: np.ndarray, tets: np.ndarray) -> np.ndarray:
    """(T,) int32 layer of each tet: the number of shells containing its centroid (0 = outside)."""
    v = model.vertices()
    c = points[tets].mean(axis=1)
    lab = np.zeros(len(tets), np.int32)
    for i in range(N_LAYERS):
        lab += igl.fast_winding_number(v, model.faces(i).astype(np.int64), c) > 0.5
    return lab


def boundary_faces(tets: np.ndarray) -> np.ndarray:
    """(B, 3) faces that belong to exactly one tet, oriented outwards (vtk ordering)."""
    local = np.array([[1, 2, 3], [0, 3, 2], [0, 1, 3], [0, 2, 1]])
    faces = tets[:, local].reshape(-1, 3)
    key = np.sort(faces, axis=1)
    _, inv, cnt = np.unique(key, axis=0, return_inverse=True, return_counts=True)
    return faces[cnt[inv.ravel()] == 1]


def region_tags(model: LayeredModel, points: np.ndarray, tets: np.ndarray) -> dict:
    """Region flags (P,) uint8 on boundary vertices: nail, support, volar on the outer surface
    (boundary faces not on a flat end cap; a rounded tip counts as the distal end of the length);
    proximal, and distal unless the tip is rounded, on the flat end caps."""
    p = model.params
    bf = boundary_faces(tets)
    tri = points[bf]
    n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    lateral = np.abs(n[:, 2]) < 0.7 * np.linalg.norm(n, axis=1)
    cap_z = tri[:, :, 2].mean(axis=1)
    proximal = ~lateral & (cap_z < model.z_mm[0] + 0.1)
    distal = ~lateral & (cap_z > model.z_mm[-1] - 0.1) & (not model.rounded)
    theta, _, _ = model.polar(points)
    zf = model.z_frac(points[:, 2])
    tol = 1e-6

    def on(faces):
        flag = np.zeros(len(points), bool)
        flag[faces.ravel()] = True
        return flag

    on_surface = on(bf[~(proximal | distal)])

    def region(centre, span_deg, z_frac):
        inside = angle_from(theta, centre) <= np.deg2rad(span_deg) / 2
        inside &= (zf >= z_frac[0] - tol) & (zf <= z_frac[1] + tol)
        return (on_surface & inside).astype(np.uint8)

    tags = {"nail": region(-np.pi / 2, p.nail_span_deg, p.nail_z_frac),
            "support": region(-np.pi / 2, p.support_span_deg, p.support_z_frac),
            "volar": region(np.pi / 2, p.volar_span_deg, (0.0, 1.0)),
            "proximal": on(bf[proximal]).astype(np.uint8)}
    if not model.rounded:
        tags["distal"] = on(bf[distal]).astype(np.uint8)
    return tags


# ---------------------------------------------------------------------- checks
def tet_volumes(points: np.ndarray, tets: np.ndarray) -> np.ndarray:
    """(T,) signed volumes, mm^3 (positive for vtk ordering)."""
    a, b, c, d = (points[tets[:, i]] for i in range(4))
    return np.einsum("ij,ij->i", b - a, np.cross(c - a, d - a)) / 6.0


def quality(points: np.ndarray, tets: np.ndarray) -> dict:
    """Min / 1st-percentile dihedral angle (deg) and scaled Jacobian (1 = regular tet), edge lengths."""
    x = points[tets]
    faces = [[1, 2, 3], [0, 3, 2], [0, 1, 3], [0, 2, 1]]
    normals = []
    for f in faces:
        nrm = np.cross(x[:, f[1]] - x[:, f[0]], x[:, f[2]] - x[:, f[0]])
        normals.append(nrm / np.linalg.norm(nrm, axis=1)[:, None])
    dihedral = []
    for i in range(4):
        for j in range(i + 1, 4):
            cos = -np.einsum("ij,ij->i", normals[i], normals[j])
            dihedral.append(np.degrees(np.arccos(np.clip(cos, -1, 1))))
    dihedral = np.min(dihedral, axis=0)
    six_v = 6 * tet_volumes(points, tets)
    edges = {(i, j): np.linalg.norm(x[:, j] - x[:, i], axis=1) for i in range(4) for j in range(i + 1, 4)}
    e = lambda i, j: edges[(min(i, j), max(i, j))]  # noqa: E731
    prods = [e(v, a) * e(v, b) * e(v, c) for v, a, b, c in ((0, 1, 2, 3), (1, 0, 2, 3), (2, 0, 1, 3), (3, 0, 1, 2))]
    sj = np.sqrt(2) * six_v / np.max(prods, axis=0)
    lengths = np.concatenate(list(edges.values()))
    return {"min_dihedral_deg": float(dihedral.min()), "p1_dihedral_deg": float(np.percentile(dihedral, 1)),
            "min_scaled_jacobian": float(sj.min()), "p1_scaled_jacobian": float(np.percentile(sj, 1)),
            "mean_scaled_jacobian": float(sj.mean()),
            "edge_mm": {"min": float(lengths.min()), "median": float(np.median(lengths)),
                        "max": float(lengths.max())}}


def straddle_check(model: LayeredModel, points: np.ndarray, tets: np.ndarray, layer: np.ndarray,
                   tol_mm: float) -> dict:
    """Tets that reach across a layer interface: a tet of layer L must have all vertices inside (or
    within tol_mm of) shell L-1 and outside (or within tol_mm of) shell L. Returns the count beyond
    tol_mm and the deepest crossing in mm."""
    v = model.vertices()
    d = np.empty((N_LAYERS, len(points)))
    for i in range(N_LAYERS):
        d[i] = igl.signed_distance(points, v, model.faces(i).astype(np.int64))[0]  # < 0 inside
    dv = d[:, tets]                                                  # (5, T, 4)
    T = np.arange(len(tets))
    outside_outer = dv[layer - 1, T].max(axis=1)                     # > 0: outside its outer shell
    inner = np.minimum(layer, N_LAYERS - 1)
    inside_inner = np.where(layer < N_LAYERS, -dv[inner, T].min(axis=1), -np.inf)  # > 0: inside next
    depth = np.maximum(outside_outer, inside_inner)
    return {"tol_mm": tol_mm, "straddling_tets": int((depth > tol_mm).sum()),
            "max_crossing_mm": float(max(depth.max(), 0.0))}


def report(model: LayeredModel, mesh: TetMesh, sizing: Sizing) -> dict:
    """Counts, volumes vs the model, quality, straddling, region sizes and sides, bone offset."""
    vol = tet_volumes(mesh.points, mesh.tets)
    lay = mesh.layer
    mesh_v = np.bincount(lay, vol, minlength=N_LAYERS + 1)[1:]
    model_v = model.layer_volumes_mm3()
    out = {"points": len(mesh.points), "tets": len(mesh.tets),
           "tets_per_layer": np.bincount(lay, minlength=N_LAYERS + 1)[1:].tolist(),
           "layer_volumes_mm3": mesh_v.tolist(), "model_layer_volumes_mm3": model_v.tolist(),
           "layer_volume_error_pct": (100 * (mesh_v / model_v - 1)).tolist(),
           "min_tet_volume_mm3": float(vol.min()),
           "quality": quality(mesh.points, mesh.tets),
           "straddle": straddle_check(model, mesh.points, mesh.tets, lay, tol_mm=2 * sizing.epsilon_mm + 1e-3)}
    cy = np.interp(mesh.points[:, 2], model.z_mm, model.centroids[:, 1])
    bf = boundary_faces(mesh.tets)
    regions = {}
    for name, flag in mesh.tags.items():
        facets = flag[bf].all(axis=1)
        tagged = flag.astype(bool)
        dy = mesh.points[tagged, 1] - cy[tagged]
        regions[name] = {"vertices": int(tagged.sum()), "facets": int(facets.sum()),
                         "y_rel_centroid_mm": [float(dy.min()), float(dy.max())] if tagged.any() else None}
    out["regions"] = regions
    out["bone_offset_mm"] = bone_offset(model, mesh.points, mesh.tets, lay, vol)
    out["sizing_achieved"] = achieved_sizes(model, mesh, sizing)
    return out


def bone_offset(model, points, tets, layer, vol) -> float:
    """Measured offset (mm, towards -y) of the bone from the section centroid: volume-weighted mean
    over bone tets of (centroid y of the section at the tet's z) - (tet centroid y)."""
    c = points[tets[layer == N_LAYERS]].mean(axis=1)
    cy = np.interp(c[:, 2], model.z_mm, model.centroids[:, 1])
    w = vol[layer == N_LAYERS]
    return float(np.sum(w * (cy - c[:, 1])) / w.sum())


def achieved_sizes(model: LayeredModel, mesh: TetMesh, sizing: Sizing) -> dict:
    """What the mesh achieved (`sizes_achieved`): the fine zone is the tets whose centroid asks for
    size_mm (the top fine_depth_mm of the volar skin); the model's rays per section besides."""
    c = mesh.points[mesh.tets].mean(axis=1)
    fine = sizing_values(model, sizing, c) <= sizing.size_mm * 1.001
    x = mesh.points[mesh.tets]
    edge = np.mean([np.linalg.norm(x[:, i] - x[:, j], axis=1) for i in range(4) for j in range(i + 1, 4)], axis=0)
    return {**sizes_achieved(mesh.points, mesh.tets, edge, mesh.layer, fine), "rays_per_section": model.rings.shape[2]}


def sizes_achieved(points: np.ndarray, cells: np.ndarray, edge: np.ndarray, layer: np.ndarray, fine: np.ndarray) -> dict:
    """The sizes a user compares meshes by (model.json `sizing_achieved`, 2D and 3D): elements and
    P2 displacement DOFs (dim x (vertices + edges)), the median and 90th-percentile element edge
    (`edge`: the mean of each element's edges, mm) in the fine zone (`fine`, per element),
    elsewhere and in each layer."""
    def stats(mask):
        e = edge[mask]
        return (int(mask.sum()), float(np.median(e)) if len(e) else None,
                float(np.percentile(e, 90)) if len(e) else None)

    dim = cells.shape[1] - 1
    pairs = np.vstack([cells[:, [i, j]] for i in range(dim + 1) for j in range(i + 1, dim + 1)])
    n_edges = len(np.unique(np.sort(pairs, axis=1), axis=0))
    n, med, p90 = stats(fine)
    rest = edge[~fine]
    return {"elements": len(cells), "dofs": dim * (len(points) + n_edges),
            "fine_zone_elements": n, "fine_zone_median_edge_mm": med, "fine_zone_p90_edge_mm": p90,
            "elsewhere_median_edge_mm": float(np.median(rest)) if len(rest) else None,
            "elsewhere_max_edge_mm": float(rest.max()) if len(rest) else None,
            "per_layer": {str(L): dict(zip(("elements", "median_edge_mm", "p90_edge_mm"), stats(layer == L)))
                          for L in np.unique(layer).tolist()}}


# ---------------------------------------------------------------------- cache and output
def cache_dir() -> Path:
    """Mesh cache folder: `fingertip.progress.cache_root()` / mesh ($FINGERTIP_CACHE_DIR, else
    ~/.cache/fingertip-fem)."""
    return cache_root() / "mesh"


def mesh_key(model: LayeredModel, sizing: Sizing) -> str:
    """sha256 of everything the tets depend on: the layer surfaces (rings, z, tip), sizing, mesher
    (and whether it runs reproducibly: an unreproducible mesh is never read for a reproducible
    one). Region parameters are left out: they change the tags, not the tets."""
    h = hashlib.sha256()
    h.update(np.ascontiguousarray(model.rings).tobytes())
    h.update(np.ascontiguousarray(model.z_mm).tobytes())
    if model.rounded:
        h.update(json.dumps([model.derived["tip_lengths_mm"], model.derived["tip_levels"]]).encode())
    h.update(json.dumps([MESHER_VERSION, asdict(sizing), metadata.version("pytetwild")] +
                        ([] if fixed_seed_library() is not None else ["unreproducible"]),
                        sort_keys=True, default=str).encode())
    return h.hexdigest()


def inputs_key(model: LayeredModel, sizing: Sizing) -> str:
    """sha256 of everything the written files depend on: the mesh key plus every model parameter."""
    extra = json.dumps([asdict(model.params), model.preset, model.sections_sha256], sort_keys=True, default=str)
    return hashlib.sha256((mesh_key(model, sizing) + extra).encode()).hexdigest()


def outputs_current(out_dir, key: str) -> bool:
    """True if out_dir holds mesh.vtu and a model.json written for these inputs."""
    out = Path(out_dir)
    try:
        return (out / "mesh.vtu").is_file() and json.loads((out / "model.json").read_text())["inputs_key"] == key
    except (OSError, ValueError, KeyError, TypeError):
        return False


def build_mesh(model: LayeredModel, sizing: Sizing, force: bool = False, progress=None):
    """Mesh the model (from the cache unless force) -> (TetMesh, info {key, cached, mesh_s,
    warnings, reproducible (whether pytetwild ran with its fixed seed, `fem.geometry.tetwild`)}).
    progress: optional `fingertip.progress` object (None: silent)."""
    progress = as_progress(progress)
    sizing.check()
    model = surface_model(model, sizing)
    key = mesh_key(model, sizing)
    path = cache_dir() / f"{key}.npz"
    t0 = time.perf_counter()
    cached, warnings = False, []
    if path.is_file() and not force:
        try:
            points, tets = read_cache_entry(path)
            cached = True
        except CacheEntryError as exc:
            warnings.append(f"mesh cache entry {path} is unreadable ({exc}); it was discarded and the mesh rebuilt")
            path.unlink(missing_ok=True)
    if cached:
        progress.note(f"mesh from cache ({path.name[:12]})")
    else:
        _, bg_t, bg_v = background_mesh(model, sizing)            # its size measure, for the estimate
        with progress.task(f"tetrahedralising with pytetwild (volar size {sizing.size_mm} mm, coarse "
                           f"{sizing.coarse_mm} mm)", kind="pytetwild", size=expected_tets(bg_t, bg_v)):
            points, tets = tetrahedralize(model, sizing)
        atomic_write(path, lambda tmp: np.savez_compressed(tmp, points=points, tets=tets))
    mesh_s = time.perf_counter() - t0
    progress.note(f"{len(tets)} tets, {len(points)} points in {mesh_s:.1f} s")
    with progress.task("labelling layers and regions", kind="label-tets", size=len(tets)):
        layer = label_tets(model, points, tets)
        mesh = TetMesh(points, tets, layer, region_tags(model, points, tets))
    return mesh, {"key": key, "cached": cached, "mesh_s": mesh_s, "warnings": warnings,
                  "reproducible": fixed_seed_library() is not None}


class CacheEntryError(Exception):
    """A mesh cache entry that cannot be used (truncated, not an .npz, wrong arrays)."""

def read_cache_entry(path) -> tuple[np.ndarray, np.ndarray]:
    """(points (P, 3) mm, tets (T, 4)) of a cache entry; CacheEntryError if it is unreadable or
    its arrays are not a tet mesh. Entries are written atomically (`build_mesh`), so a bad one
    comes from outside the toolkit (a full disk, a copy cut short)."""
    try:
        with np.load(path) as d:
            points, tets = np.asarray(d["points"], float), np.asarray(d["tets"])
    except Exception as exc:  # noqa: BLE001 - np.load raises BadZipFile, OSError, ValueError, KeyError, EOFError, zlib.error
        raise CacheEntryError(f"{type(exc).__name__}: {exc}") from None
    if (points.ndim != 2 or points.shape[1] != 3 or tets.ndim != 2 or tets.shape[1] != 4 or not len(tets)
            or tets.dtype.kind not in "iu" or tets.min() < 0 or tets.max() >= len(points)
            or not np.isfinite(points).all()):
        raise CacheEntryError(f"points {points.shape}, tets {tets.shape} {tets.dtype} are not a tet mesh")
    return points, tets


def write_mesh(out_dir, model: LayeredModel, sizing: Sizing, mesh: TetMesh, rep: dict, info: dict) -> None:
    """Write mesh.vtu and model.json into out_dir atomically."""
    data = model.to_json()
    data.update({"inputs_key": inputs_key(model, sizing), "sizing": asdict(sizing),
                 "mesh": {**rep, "cache_key": info["key"], "from_cache": info["cached"], "mesh_seconds": info["mesh_s"],
                          "reproducible": info["reproducible"],
                          "file": "mesh.vtu", "cells": "tetra (linear, positive orientation)"}})
    with staged_output(out_dir) as tmp:
        meshio.write(tmp / "mesh.vtu", mesh.to_meshio())
        write_json(tmp / "model.json", data)


def summary(rep: dict, info: dict, out_dir) -> str:
    """One-screen text summary of a mesh report."""
    q, s = rep["quality"], rep["straddle"]
    names = ["epidermis", "dermis", "layer 3", "layer 4", "bone"]
    lines = [f"mesh.vtu + model.json in {out_dir}",
             f"  {rep['tets']} tets, {rep['points']} points ({'cache' if info['cached'] else 'pytetwild'} "
             f"{info['mesh_s']:.1f} s)",
             "  layer        tets   volume mm3   model mm3   error %"]
    for i, n in enumerate(names):
        lines.append(f"  {i + 1} {n:<9} {rep['tets_per_layer'][i]:>7} {rep['layer_volumes_mm3'][i]:>11.2f} "
                     f"{rep['model_layer_volumes_mm3'][i]:>11.2f} {rep['layer_volume_error_pct'][i]:>8.2f}")
    a = rep["sizing_achieved"]
    lines += [f"  quality: min dihedral {q['min_dihedral_deg']:.1f} deg (1st pct {q['p1_dihedral_deg']:.1f}), "
              f"min scaled Jacobian {q['min_scaled_jacobian']:.3f} (mean {q['mean_scaled_jacobian']:.2f})",
              f"  straddling tets: {s['straddling_tets']} (deepest crossing {s['max_crossing_mm']:.3f} mm, "
              f"tolerance {s['tol_mm']:.3f} mm)",
              f"  {a['dofs']} DOFs (P2), {a['rays_per_section']} rays per section; median edge (90th pct): "
              f"volar fine zone {_mm(a['fine_zone_median_edge_mm'])} ({_mm(a['fine_zone_p90_edge_mm'])}) mm, "
              f"elsewhere {_mm(a['elsewhere_median_edge_mm'])} mm; per layer "
              + " ".join(_mm(v["median_edge_mm"], 2) for v in a["per_layer"].values()) + " mm",
              f"  bone offset towards the nail: {rep['bone_offset_mm']:.3f} mm",
              "  regions: " + ", ".join(f"{k} {v['facets']} facets" for k, v in rep["regions"].items())]
    return "\n".join(lines)


def _mm(v: float | None, digits: int = 3) -> str:
    """A length for the summary; 'none' where no element was measured (a zone the mesh has no
    element centroid in, as the volar fine zone of a mesh coarser than it is deep)."""
    return "none" if v is None else f"{v:.{digits}f}"


def run_mesh(out_dir, model: LayeredModel, sizing: Sizing, force: bool = False, progress=None):
    """Build (or load), check and write the mesh of `model`; returns (TetMesh, report, info), or
    None when out_dir already holds the outputs of these inputs (and not force). progress:
    optional `fingertip.progress` object, or True for one on stderr (None: silent)."""
    sizing.check()
    model = surface_model(model, sizing)
    if not force and outputs_current(out_dir, inputs_key(model, sizing)):
        return None
    progress = as_progress(progress)
    mesh, info = build_mesh(model, sizing, force=force, progress=progress)
    with progress.task("checking the mesh", kind="mesh-report", size=len(mesh.tets)):
        rep = report(model, mesh, sizing)
    write_mesh(out_dir, model, sizing, mesh, rep, info)
    return mesh, rep, info
