"""Layered fingertip model (thesis 6.1): five nested layer surfaces, offset bone, nail and support.

Every axial section is resampled on N rays from its centroid (same angles in every section):

    ring 0  outer skin surface                 (outer boundary of layer 1, epidermis)
    ring 1  offset of ring 0 by epidermis_mm   (1 | 2)
    ring 2  offset by epidermis_mm + dermis_mm (2 | 3)
    ring 3  ring 0 scaled about the centroid by 1 - f3 (3 | 4), f3 from three reference sections
    ring 4  bone: ring 0 scaled by bone width / section width, shifted by bone_offset_mm towards -y

Offsets are exact erosions of the convex section (half-planes moved inwards), so the skin has the
given thickness all round. Rings 0-3 share their rays; the bone is a homothetic copy of ring 0
whose centre lies inside the bone, so corresponding ring points never cross. Layers are straight
prisms between sections with a flat proximal cap. Distally they end in a flat cap too (the thesis
did not model the hemispherical tip), or, with tip_mm > 0, each shell closes in a dome: its last
ring scaled by cos(phi) about its centre at z1 + h sin(phi), phi in [0, pi/2]. The outer dome is
tip_mm long; the skin shells are shorter by their depth, ring 3's and the bone's by their scale
factors, so every layer wraps round the tip with its own thickness (thesis 6.1: "the various
layers of the skin could be wrapped around the bone at the distal end").
"""
from __future__ import annotations

import json
from dataclasses import asdict, dataclass, field, replace

import igl
import numpy as np

from fem.core.materials import DEFAULT_NU, LAYERED_CODE
from fem.geometry.presets import FINGERTIP_PRESETS
from fem.geometry.sections import (
    body_z_range,
    check_polygon,
    load_sections,
    preset_sections,
    smooth_polygon,
    tip_length,
)
from fingertip.declare import declared, finite, nonnegative, positive
from fingertip.errors import InputError

N_LAYERS = 5
REFERENCE_RAYS = 64
"""Rays on which `LayeredModel.rays_for` measures the facets of the outer surface."""
MAX_RAYS = 4096
"""Most rays per section a resampled model has (`LayeredModel.rays_for`)."""
RAY_BLOCK_ENTRIES = 2**22
"""Ray-edge pairs per block of `_ray_exit` (32 MB of float64)."""
#: Per-preset layer-3 thickness and bone offset (not in the thesis; the monkey section is too thin
#: for the human values: its dorsal half-height is 2.5 mm, the human's 5.0 mm).
PRESET_PARAMS = {
    "human": dict(layer3_mm=1.5, bone_offset_mm=1.0),
    "monkey": dict(layer3_mm=0.55, bone_offset_mm=0.15),
}
#: Middle-section width (mm) of each preset's sections (thesis 3.3.1: human about 16, monkey about 8 mm wide;
#: the presets taper to 17.12 and 8.56 mm at the middle reference section).
PRESET_MIDDLE_WIDTH_MM = {"human": 17.12, "monkey": 8.56}
SIZED_PARAMS = ("layer3_mm", "bone_offset_mm")
SIZE_RULE = ("parameters not given: linear in the middle-section width between the presets "
             + ", ".join(f"{k} ({PRESET_MIDDLE_WIDTH_MM[k]} mm: {PRESET_PARAMS[k]})" for k in ("monkey", "human"))
             + "; the nearer preset's values outside")


def check_positive(obj, *names: str) -> None:
    """Raise InputError unless every named attribute of obj is > 0."""
    for name in names:
        if not getattr(obj, name) > 0:
            value = getattr(obj, name)
            raise InputError(f"{name} must be > 0, got {value:g}" if isinstance(value, (int, float))
                             else f"{name} must be > 0, got {value!r}")


def parse_profile(text: str | None):
    """A bone profile in words, 's:ratio,s:ratio,...' -> ((s, ratio), ...) (None -> None);
    ValueError for other words."""
    if text is None:
        return None
    try:
        rows = tuple(tuple(float(v) for v in item.split(":")) for item in text.split(","))
    except ValueError:
        raise ValueError(f"'{text}': expected 's:ratio,...' numbers, e.g. 0:0.25,1:0.18") from None
    if any(len(r) != 2 for r in rows):
        raise ValueError(f"'{text}': each item is s:ratio, e.g. 0:0.25,1:0.18")
    return rows


def parse_tip(text: str):
    """The distal end in words: 'flat' -> 0.0, 'rounded' -> None (the data's length), a number ->
    that dome length in mm; ValueError for other words."""
    if text in ("flat", "rounded"):
        return 0.0 if text == "flat" else None
    try:
        return float(text)
    except ValueError:
        raise ValueError(f"'{text}': use flat, rounded or a dome length in mm, e.g. 6.5") from None


@dataclass(frozen=True)
class ModelParams:
    """Every parameter of the layered model. Lengths in mm, angles in degrees.

    layer3_mm: thickness of layer 3 on the volar side at the three reference sections; it sets
        the thesis scale factor f3 = (epidermis + dermis + layer3) / volar half-thickness (mean of
        the sections at 25, 50, 75 % of the length), then used for every section. None: chosen by
        the section size (`size_defaults`), as is bone_offset_mm.
    layer3_scale: give f3 directly instead (overrides layer3_mm).
    bone_profile: ((s, ratio), ...) with s = (z - z0) / (z1 - z0) in [0, 1] and ratio = bone width
        / section width, linearly interpolated; None: a constant ratio giving bone_diameter_mm at
        the middle reference section.
    nail_*, support_*: angular span centred on -y (dorsal) and z range as fractions of the length.
    volar_*: the volar surface region, span centred on +y, over the whole length.
    support_incline_deg: angle of the support plane to the horizontal, positive with the distal
        end lower (-30 for the thesis's platform, distal end up); the support normal in the finger frame is +y (the finger lies on it), and
        `vertical_up` in model.json is +y turned by this angle about x (distal end lower).
    n_theta: rays per section of the model; a mesh resamples the sections on more rays
        (`LayeredModel.resampled`, `LayeredModel.rays_for`) so that its surface facets are well below
        its element size.
    tip_mm: length (mm) of the rounded distal tip beyond the last section; 0: a flat distal cut (the
        thesis's model); None: the length of the data (`model_from_args`: the preset's cap, or the
        sections beyond the body).
    """
    epidermis_mm: float = declared(0.5, "mm", "epidermis thickness", text=positive)
    dermis_mm: float = declared(1.0, "mm", "dermis thickness", text=positive)
    layer3_mm: float | None = declared(None, "mm", "layer 3 volar thickness at the reference sections; sets the "
                                       "thesis scale factor", text=positive, default_text="presets human 1.5, monkey 0.55; "
                                       "sections.json by section width, see model.json size_defaults")
    layer3_scale: float | None = declared(None, "", "the layer-3 scale factor f3 directly (0-1; overrides layer3)",
                                          text=positive)
    bone_diameter_mm: float = declared(2.0, "mm", "bone width at the middle reference section", text=positive)
    bone_profile: tuple | None = declared(None, "", "bone width / section width along the length, 's:ratio,...' "
                                          "with s in [0, 1] from proximal to distal, e.g. 0:0.25,1:0.18",
                                          text=parse_profile, default_text="constant")
    bone_offset_mm: float | None = declared(None, "mm", "bone shift towards the nail (-y)", text=nonnegative,
                                            default_text="presets human 1.0, monkey 0.15; sections.json by width")
    nail_span_deg: float = declared(120.0, "deg", "nail region angular span", text=positive)
    nail_z_frac: tuple = declared((0.3, 1.0), "", "nail region as fractions of the length (LO HI)", text=finite,
                                  nargs=2)
    support_span_deg: float = declared(90.0, "deg", "support region angular span", text=positive)
    support_z_frac: tuple = declared((0.0, 0.3), "", "support region as fractions of the length (LO HI)",
                                     text=finite, nargs=2)
    support_incline_deg: float = declared(0.0, "deg", "support plane angle to the horizontal, positive with the "
                                          "distal end lower (-30: the thesis platform, distal end up)", text=finite)
    volar_span_deg: float = 180.0
    n_theta: int = 64
    tip_mm: float | None = declared(0.0, "mm", "distal end: flat (a cut, as the thesis), rounded (every layer "
                                    "wraps round a dome as long as the data's tip: the preset's cap, the sections "
                                    "beyond the body), or the dome length in mm", text=parse_tip,
                                    default_text="flat")

    def check(self) -> None:
        """Raise InputError for impossible values."""
        check_positive(self, "epidermis_mm", "dermis_mm", "bone_diameter_mm")
        if self.layer3_mm is not None:
            check_positive(self, "layer3_mm")
        if self.bone_offset_mm is not None and self.bone_offset_mm < 0:
            raise InputError(f"bone_offset_mm must be >= 0 (towards the nail, -y); got {self.bone_offset_mm}")
        if self.layer3_scale is not None and not 0 < self.layer3_scale < 1:
            raise InputError(f"layer3_scale must be in (0, 1); got {self.layer3_scale}")
        for name in ("nail_span_deg", "support_span_deg", "volar_span_deg"):
            if not 0 < getattr(self, name) <= 360:
                raise InputError(f"{name} must be in (0, 360]; got {getattr(self, name)}")
        for name in ("nail_z_frac", "support_z_frac"):
            lo, hi = getattr(self, name)
            if not 0 <= lo < hi <= 1:
                raise InputError(f"{name} must be two fractions 0 <= lo < hi <= 1; got {lo} {hi}")
        if not -90 < self.support_incline_deg < 90:
            raise InputError(f"support_incline_deg must be in (-90, 90); got {self.support_incline_deg}")
        if self.tip_mm is not None and self.tip_mm < 0:
            raise InputError(f"tip_mm must be >= 0 (0: flat distal cut); got {self.tip_mm}")
        if self.n_theta < 16:
            raise InputError(f"n_theta must be >= 16; got {self.n_theta}")
        if self.bone_profile is not None:
            prof = np.asarray(self.bone_profile, float)
            if prof.ndim != 2 or prof.shape[1] != 2 or len(prof) < 1:
                raise InputError("bone_profile must be rows (s, ratio), e.g. 0:0.25,1:0.2")
            if np.any(np.diff(prof[:, 0]) <= 0) or prof[0, 0] < 0 or prof[-1, 0] > 1:
                raise InputError("bone_profile: s must increase within [0, 1]")
            if np.any(prof[:, 1] <= 0) or np.any(prof[:, 1] >= 1):
                raise InputError("bone_profile: ratio (bone width / section width) must be in (0, 1)")


@dataclass
class LayeredModel:
    """The layered solid. z_mm: (K,); rings: (K, 5, N, 2) interface curves (x, y) in mm;
    centroids: (K, 2) section centroids (the ray origin); polygons: the K checked section outlines
    the rings sample (so that `resampled` gives the same model on more rays)."""
    z_mm: np.ndarray
    rings: np.ndarray
    centroids: np.ndarray
    params: ModelParams
    preset: str | None = None
    sections_sha256: str = ""
    derived: dict = field(default_factory=dict)
    polygons: list = field(default_factory=list, repr=False)

    # ------------------------------------------------------------------ resolution
    def rays_for(self, facet_mm: float) -> int:
        """Rays per section (a multiple of 8, at least n_theta, at most MAX_RAYS) for which the
        longest facet of the outer surface is about facet_mm (within 5 %): estimated from the facets
        on REFERENCE_RAYS rays of the sections, so the answer does not depend on the rays the model has."""
        K, N = len(self.polygons), REFERENCE_RAYS
        u = _ray_directions(N)
        longest = 0.0
        for p, c in zip(self.polygons, self.centroids):
            ring = c + _ray_exit(p, c, u, 0.0)[:, None] * u
            longest = max(longest, float(np.linalg.norm(np.roll(ring, -1, axis=0) - ring, axis=1).max()))
        need = 8 * int(np.ceil(N * longest / facet_mm / 8)) if K else 0
        return int(min(MAX_RAYS, max(self.params.n_theta, need)))

    def resampled(self, n_theta: int) -> LayeredModel:
        """The same model (its scale factors kept) on n_theta rays per section: every ring again
        the exact ray exits of its section's outline and its offsets."""
        if n_theta == self.rings.shape[2]:
            return self
        return _layered(self.z_mm, self.polygons, self.centroids, replace(self.params, n_theta=int(n_theta)),
                        self.derived, self.preset, self.sections_sha256)

    def section_rings(self, z_mm: float, n_theta: int, smooth_mm: float | None = None) -> tuple[np.ndarray, np.ndarray]:
        """((5, n_theta, 2) rings, (2,) centroid) of the cross-section at z_mm (within the sections):
        the two neighbouring sections on n_theta rays, interpolated linearly, as the prisms between
        them are. smooth_mm: the sections as smooth curves sampled that finely
        (`fem.geometry.sections.smooth_polygon`) instead of their polygons."""
        z = self.z_mm
        k = int(np.clip(np.searchsorted(z, z_mm) - 1, 0, len(z) - 2))
        w = (z_mm - z[k]) / (z[k + 1] - z[k])
        u, skin = _ray_directions(int(n_theta)), _skin_depths(self.params)
        outlines = [self.polygons[j] if smooth_mm is None else smooth_polygon(self.polygons[j], smooth_mm)
                    for j in (k, k + 1)]
        rings = [_section_rings(p, self.centroids[j], u, skin, self.derived, j, z[j])
                 for p, j in zip(outlines, (k, k + 1))]
        return (1 - w) * rings[0] + w * rings[1], (1 - w) * self.centroids[k] + w * self.centroids[k + 1]

    # ------------------------------------------------------------------ surfaces
    @property
    def rounded(self) -> bool:
        """True if the shells close in domes distally (tip_mm > 0), False for a flat distal cut."""
        return "tip_lengths_mm" in self.derived

    def _flat_ends(self) -> tuple:
        """Sections closed by a flat cap: the proximal one, and the distal one unless rounded."""
        return (0,) if self.rounded else (0, len(self.z_mm) - 1)

    def _vertex_index(self):
        """Vertex ids: rings (K, 5, N); flat cap centres (1 or 2,); dome levels (5, M-1, N) and
        apexes (5,), both None for a flat distal cut."""
        K, _, N, _ = self.rings.shape
        n = K * N_LAYERS * N
        ring_id = np.arange(n).reshape(K, N_LAYERS, N)
        centres = n + np.arange(len(self._flat_ends()))
        if not self.rounded:
            return ring_id, centres, None, None
        n += len(centres)
        M = self.derived["tip_levels"]
        levels = n + np.arange(N_LAYERS * (M - 1) * N).reshape(N_LAYERS, M - 1, N)
        return ring_id, centres, levels, n + levels.size + np.arange(N_LAYERS)

    def _domes(self):
        """Distal domes: level rings (5, M-1, N, 3) and apexes (5, 3), mm. Shell i's last ring is
        scaled by cos(phi) about its centre (centroid; bone: bone centre) at z1 + h_i sin(phi)."""
        h = np.asarray(self.derived["tip_lengths_mm"])
        M = self.derived["tip_levels"]
        phi = 0.5 * np.pi * np.arange(1, M) / M
        K = len(self.z_mm)
        centre = np.vstack([np.tile(self.centroids[-1], (N_LAYERS - 1, 1)), self.bone_centre(K - 1)])
        rel = self.rings[-1] - centre[:, None]                                     # (5, N, 2)
        xy = centre[:, None, None] + np.cos(phi)[None, :, None, None] * rel[:, None]
        z = self.z_mm[-1] + h[:, None] * np.sin(phi)[None]                         # (5, M-1)
        levels = np.concatenate([xy, np.broadcast_to(z[:, :, None, None], xy.shape[:3] + (1,))], axis=-1)
        return levels, np.column_stack([centre, self.z_mm[-1] + h])

    def vertices(self) -> np.ndarray:
        """(V, 3) vertices: all rings, the bone-cap centres of the flat ends, then the dome levels
        and apexes of a rounded tip (ids as `_vertex_index`)."""
        K, _, N, _ = self.rings.shape
        xyz = np.concatenate([self.rings, np.broadcast_to(self.z_mm[:, None, None, None],
                                                          (K, N_LAYERS, N, 1))], axis=-1)
        ends = np.array([[*self.bone_centre(k), self.z_mm[k]] for k in self._flat_ends()])
        out = [xyz.reshape(-1, 3), ends]
        if self.rounded:
            levels, apex = self._domes()
            out += [levels.reshape(-1, 3), apex]
        return np.vstack(out)

    def bone_centre(self, k: int) -> np.ndarray:
        """Centre of the homothety that maps ring 0 to the bone in section k (inside the bone)."""
        rho, b = self.derived["bone_ratio"][k], self.derived["bone_shift"][k]
        return self.centroids[k] + np.asarray(b) / (1.0 - rho)

    def faces(self, ring: int | None = None) -> np.ndarray:
        """Outward triangles (M, 3). ring=None: the merged input of all shells (each face once);
        ring=i: the closed shell bounding layers i+1..5 (ring i's tube, its end caps or dome)."""
        K, _, N, _ = self.rings.shape
        ids, centres, levels, apex = self._vertex_index()
        j, j1 = np.arange(N), (np.arange(N) + 1) % N

        def strips(lo, hi):
            """Triangles between consecutive rings lo, hi (..., N) of ids, outward as the tubes."""
            a, b, c, d = lo[..., j], lo[..., j1], hi[..., j1], hi[..., j]
            return np.vstack([np.stack([a, b, c], -1).reshape(-1, 3), np.stack([a, c, d], -1).reshape(-1, 3)])

        rings = range(N_LAYERS) if ring is None else [ring]
        out = [strips(ids[:-1, i], ids[1:, i]) for i in rings]                     # lateral tubes
        first = 0 if ring is None else ring
        for k, centre in zip(self._flat_ends(), centres):
            cap = []
            for i in range(first, N_LAYERS - 1):          # annuli between rings i and i+1
                o, o1, n, n1 = ids[k, i, j], ids[k, i, j1], ids[k, i + 1, j], ids[k, i + 1, j1]
                cap += [np.stack([o, o1, n1], -1), np.stack([o, n1, n], -1)]
            bone = ids[k, N_LAYERS - 1]
            cap.append(np.stack([np.full(N, centre), bone[j], bone[j1]], -1))
            cap = np.vstack(cap)
            out.append(cap[:, ::-1] if k == 0 else cap)
        if self.rounded:
            for i in rings:
                seq = np.vstack([ids[-1, i][None], levels[i]])                    # (M, N)
                out += [strips(seq[:-1], seq[1:]), np.stack([seq[-1, j], seq[-1, j1], np.full(N, apex[i])], -1)]
        return np.vstack(out)

    def shell_volumes_mm3(self) -> np.ndarray:
        """(5,) volumes enclosed by rings 0..4 (exact for the piecewise-linear surfaces)."""
        v = self.vertices()
        vols = []
        for i in range(N_LAYERS):
            f = v[self.faces(i)]
            vols.append(np.einsum("ij,ij->i", f[:, 0], np.cross(f[:, 1], f[:, 2])).sum() / 6.0)
        return np.array(vols)

    def layer_volumes_mm3(self) -> np.ndarray:
        """(5,) volume of each layer of the model geometry."""
        s = self.shell_volumes_mm3()
        return s - np.append(s[1:], 0.0)

    # ------------------------------------------------------------------ lookups
    def outer_radius(self, theta: np.ndarray, z: np.ndarray) -> np.ndarray:
        """Radius (mm) of the outer surface from the interpolated centroid, at angles/z (same shape);
        on a rounded tip, the outer dome's."""
        K, _, N, _ = self.rings.shape
        r = np.linalg.norm(self.rings[:, 0] - self.centroids[:, None], axis=-1)      # (K, N)
        t = (np.mod(theta, 2 * np.pi) / (2 * np.pi)) * N
        j0 = np.floor(t).astype(int) % N
        wj = t - np.floor(t)
        kf = np.interp(z, self.z_mm, np.arange(K))
        k0 = np.clip(np.floor(kf).astype(int), 0, max(K - 2, 0))
        wk = np.clip(kf - k0, 0, 1)
        k1 = np.minimum(k0 + 1, K - 1)
        rk0 = (1 - wj) * r[k0, j0] + wj * r[k0, (j0 + 1) % N]
        rk1 = (1 - wj) * r[k1, j0] + wj * r[k1, (j0 + 1) % N]
        R = (1 - wk) * rk0 + wk * rk1
        if self.rounded:                                  # the outer dome beyond the last section
            u = np.clip((np.asarray(z) - self.z_mm[-1]) / self.derived["tip_lengths_mm"][0], 0.0, 1.0)
            R = R * np.sqrt(1.0 - u**2)
        return R

    def polar(self, points: np.ndarray):
        """(theta, r, outer radius) of (M, 3) points about the interpolated section centroid."""
        cx = np.interp(points[:, 2], self.z_mm, self.centroids[:, 0])
        cy = np.interp(points[:, 2], self.z_mm, self.centroids[:, 1])
        dx, dy = points[:, 0] - cx, points[:, 1] - cy
        theta = np.arctan2(dy, dx)
        return theta, np.hypot(dx, dy), self.outer_radius(theta, points[:, 2])

    def z_frac(self, z: np.ndarray) -> np.ndarray:
        """Fraction of the length from the proximal to the last section, clipped to [0, 1] (a
        rounded tip counts as the distal end)."""
        return np.clip((z - self.z_mm[0]) / (self.z_mm[-1] - self.z_mm[0]), 0.0, 1.0)

    def to_json(self) -> dict:
        """Every parameter and derived number of the model (for model.json)."""
        p = self.params
        a = np.deg2rad(p.support_incline_deg)
        return {
            "preset": self.preset, "units": "mm", "sections_sha256": self.sections_sha256,
            "z_range_mm": [float(self.z_mm[0]), float(self.z_mm[-1])], "n_sections": len(self.z_mm),
            "params": _jsonable(asdict(p)),
            "layers": {"1": "epidermis", "2": "dermis", "3": "inner soft layer (adipose)",
                       "4": "inner soft layer (fibrous matrix)", "5": "bone"},
            "layer3_scale_factor": self.derived["f3"],
            "reference_sections_z_mm": self.derived["ref_z"],
            "bone_ratio_range": [float(min(self.derived["bone_ratio"])), float(max(self.derived["bone_ratio"]))],
            "bone_diameter_range_mm": self.derived["bone_width_range"],
            "size_defaults": {**self.derived["size_defaults"], "rule": SIZE_RULE},
            "min_layer_thickness_mm": self.derived["min_thickness"],
            "model_layer_volumes_mm3": [float(v) for v in self.layer_volumes_mm3()],
            "material": LAYERED_CODE, "nu": DEFAULT_NU,
            "region_angles_about": "the section centroid at each z; centre = direction of the span's middle",
            "regions": {
                "nail": {"fixed": "all displacements", "span_deg": p.nail_span_deg, "centre": [0, -1],
                         "z_frac": list(p.nail_z_frac)},
                "support": {"fixed": "displacement along the support normal", "normal": [0.0, 1.0, 0.0],
                            "span_deg": p.support_span_deg, "centre": [0, -1], "z_frac": list(p.support_z_frac),
                            "incline_deg": p.support_incline_deg,
                            "vertical_up": [0.0, float(np.cos(a)), 0.0 - float(np.sin(a))]},
                "volar": {"span_deg": p.volar_span_deg, "centre": [0, 1], "z_frac": [0.0, 1.0]},
                "proximal": {"what": "flat proximal cut (end cap at z0), where the finger goes on",
                             "fixed": "its core (layers 3-5), all displacements (fem.io.modelfolder.HELD: the hand "
                                      "is held; the skin goes on)"},
                **({"tip": {"what": "rounded distal tip: each shell closes in a dome beyond z1, free",
                            "dome_lengths_mm": self.derived["tip_lengths_mm"],
                            "min_layer_thickness_mm": self.derived["min_thickness_tip"]}} if self.rounded else
                   {"distal": {"what": "flat distal cut where the rounded tip starts (end cap at z1), free"}}),
            },
        }


def _jsonable(d):
    return json.loads(json.dumps(d, default=lambda o: o.tolist() if hasattr(o, "tolist") else list(o)))


# ---------------------------------------------------------------------- model
def build_model(z_mm, polygons, params: ModelParams = ModelParams(), preset: str | None = None,
                sections_sha256: str = "") -> LayeredModel:
    """Layered model from K sections: z_mm (K,) increasing, polygons [(n_k, 2)] convex, mm."""
    params.check()
    z = np.asarray(z_mm, float)
    if len(z) < 2:
        raise InputError(f"need at least 2 sections along z, got {len(z)}")
    if np.any(np.diff(z) <= 0):
        raise InputError("section z values must be strictly increasing (sort them, remove duplicates)")
    polys = [check_polygon(p, f"section at z={zi:g} mm") for zi, p in zip(z, polygons)]
    ref_z = [float(np.interp(f, [0, 1], [z[0], z[-1]])) for f in (0.25, 0.5, 0.75)]
    middle_width = float(np.interp(ref_z[1], z, [np.ptp(p[:, 0]) for p in polys]))
    unset = [k for k in SIZED_PARAMS if getattr(params, k) is None
             and not (k == "layer3_mm" and params.layer3_scale is not None)]
    chosen = {k: v for k, v in size_defaults(middle_width).items() if k in unset}
    params = replace(params, **chosen)
    N = params.n_theta
    u = _ray_directions(N)
    skin = _skin_depths(params)
    K = len(z)
    cents = np.array([_centroid(p) for p in polys])
    outer = np.array([_skin_rings(p, c, u, skin, zi)[0] for p, c, zi in zip(polys, cents, z)])     # (K, N, 2)
    # thesis scaling: f3 = thickness / section thickness at three reference sections
    r0 = np.linalg.norm(outer - cents[:, None], axis=-1)                       # (K, N)
    volar = N // 4                                                            # ray towards +y
    volar_thick = np.array([np.interp(zr, z, r0[:, volar]) for zr in ref_z])
    if params.layer3_scale is not None:
        f3 = params.layer3_scale
    else:
        f3 = float(np.mean((skin[2] + params.layer3_mm) / volar_thick))
    if f3 >= 1:
        raise InputError(f"layer 3 ({params.layer3_mm} mm) plus skin is thicker than the section "
                         f"(volar half-thickness {volar_thick.min():.2f} mm); use a smaller layer3_mm")
    # bone: scaled copy of the profile, shifted towards the nail
    width = np.ptp(outer[..., 0], axis=1)
    s = (z - z[0]) / (z[-1] - z[0])
    if params.bone_profile is None:
        ratio = np.full(K, params.bone_diameter_mm / np.interp(ref_z[1], z, width))
    else:
        prof = np.asarray(params.bone_profile, float)
        ratio = np.interp(s, prof[:, 0], prof[:, 1])
    shift = [0.0, -params.bone_offset_mm]
    derived = {"f3": f3, "ref_z": ref_z, "bone_ratio": ratio.tolist(), "bone_shift": [shift] * K,
               "bone_width_range": [float((ratio * width).min()), float((ratio * width).max())],
               "size_defaults": {"middle_width_mm": middle_width, "chosen": chosen}}
    if params.tip_mm is None:
        raise InputError("tip_mm None (the data's tip length) is resolved by model_from_args; give a length")
    return _layered(z, polys, cents, params, derived, preset, sections_sha256)


def _layered(z, polys, cents, params: ModelParams, derived: dict, preset, sections_sha256) -> LayeredModel:
    """The model of checked sections with their scale factors (derived f3, bone_ratio, bone_shift):
    the rings on params.n_theta rays, nesting checked, the domes of a rounded tip."""
    N, skin = params.n_theta, _skin_depths(params)
    u = _ray_directions(N)
    rings = np.array([_section_rings(p, c, u, skin, derived, k, zk)
                      for k, (p, c, zk) in enumerate(zip(polys, cents, z))])
    derived = {**derived, "min_thickness": _check_nesting(z, rings, cents)}
    if params.tip_mm > 0:
        derived.update(_dome_lengths(params.tip_mm, skin, derived["f3"], derived["bone_ratio"][-1], rings[-1, 0],
                                     cents[-1], N))
    model = LayeredModel(z, rings, cents, params, preset, sections_sha256, derived, polys)
    if model.rounded:
        derived["min_thickness_tip"] = _check_dome_nesting(model)
    return model


def _skin_depths(params: ModelParams) -> tuple:
    """Depths (mm) of rings 0-2 below the outer surface."""
    return (0.0, params.epidermis_mm, params.epidermis_mm + params.dermis_mm)


def _skin_rings(p, c, u, skin, z_mm) -> np.ndarray:
    """(3, N, 2) rings 0-2 of section p (centroid c) on rays u: exact erosions by the skin depths."""
    out = np.empty((len(skin), len(u), 2))
    for i, d in enumerate(skin):
        t = _ray_exit(p, c, u, d)
        if np.any(t <= 1e-6):
            raise InputError(f"section at z={z_mm:g} mm: the skin (epidermis + dermis = {skin[-1]:g} mm) is "
                             "thicker than the section; use thinner layers or a shorter z range")
        out[i] = c + t[:, None] * u
    return out


def _section_rings(p, c, u, skin, derived: dict, k: int, z_mm) -> np.ndarray:
    """(5, N, 2) rings of section k (outline p, centroid c) on rays u: the skin's erosions, ring 0
    scaled about c by 1 - f3, and the bone: ring 0 scaled by its ratio, shifted towards the nail."""
    skin_rings = _skin_rings(p, c, u, skin, z_mm)
    ring3 = c + (1 - derived["f3"]) * (skin_rings[0] - c)
    bone = c + np.asarray(derived["bone_shift"][k]) + derived["bone_ratio"][k] * (skin_rings[0] - c)
    return np.concatenate([skin_rings, ring3[None], bone[None]])


def _dome_lengths(tip_mm, skin, f3, bone_ratio, outer_ring, centre, N) -> dict:
    """Dome lengths (mm) of the 5 shells beyond the last section and the number of dome levels.
    Skin shells are shorter by their depth, ring 3 and the bone by their scale factors."""
    h = np.array([tip_mm, tip_mm - skin[1], tip_mm - skin[2], (1 - f3) * tip_mm, bone_ratio * tip_mm])
    if np.any(np.diff(h) >= 0) or h[-1] <= 0:
        need = 1.05 * skin[2] / f3                          # the dermis' dome must pass layer 3's
        raise InputError(f"tip_mm {tip_mm:g} is too short to wrap the layers round the tip (dome lengths "
                         + ", ".join(f"{v:.2f}" for v in h) + f" mm must decrease inwards); use at least "
                         f"{need:.2f} mm, or 0 for a flat distal cut")
    r_volar = float(np.linalg.norm(outer_ring[N // 4] - centre))
    arc = 0.5 * np.pi * np.sqrt(0.5 * (r_volar**2 + tip_mm**2))       # quarter-ellipse length, mm
    edge = float(np.mean(np.linalg.norm(np.roll(outer_ring, -1, axis=0) - outer_ring, axis=1)))
    return {"tip_lengths_mm": h.tolist(), "tip_levels": max(4, int(np.ceil(arc / edge)))}


def _check_dome_nesting(model: LayeredModel) -> list[float]:
    """Each dome strictly inside the next outer shell: min distance (mm) of dome i+1's vertices
    from shell i, i = 0..3. Raises InputError where they touch or cross."""
    v = model.vertices()
    _, _, levels, apex = model._vertex_index()
    out = []
    for i in range(N_LAYERS - 1):
        pts = v[np.append(levels[i + 1].ravel(), apex[i + 1])]
        d = -igl.signed_distance(pts, v, model.faces(i).astype(np.int64))[0]      # > 0 inside
        if d.min() <= 1e-3:
            raise InputError(f"the rounded tip: shell {i + 1}'s dome reaches shell {i}'s "
                             "(use a longer tip_mm, thinner layers or a smaller bone)")
        out.append(float(d.min()))
    return out


def size_defaults(middle_width_mm: float) -> dict:
    """{layer3_mm, bone_offset_mm} for sections of this width (mm) at the middle reference section:
    linear in the width between the monkey and human presets' values at their middle widths
    (PRESET_MIDDLE_WIDTH_MM), the nearer preset's values outside that range."""
    lo, hi = PRESET_MIDDLE_WIDTH_MM["monkey"], PRESET_MIDDLE_WIDTH_MM["human"]
    t = float(np.clip((middle_width_mm - lo) / (hi - lo), 0.0, 1.0))
    return {k: round((1 - t) * PRESET_PARAMS["monkey"][k] + t * PRESET_PARAMS["human"][k], 3)
            for k in SIZED_PARAMS}


def _centroid(p: np.ndarray) -> np.ndarray:
    x, y = p[:, 0], p[:, 1]
    cr = x * np.roll(y, -1) - np.roll(x, -1) * y
    a = cr.sum() / 2
    return np.array([((x + np.roll(x, -1)) * cr).sum(), ((y + np.roll(y, -1)) * cr).sum()]) / (6 * a)


def _ray_directions(n: int) -> np.ndarray:
    """(n, 2) unit vectors of the rays, from +x counter-clockwise (ray n // 4 towards +y)."""
    theta = 2 * np.pi * np.arange(n) / n
    return np.column_stack([np.cos(theta), np.sin(theta)])


def _ray_exit(p: np.ndarray, c: np.ndarray, u: np.ndarray, d: float) -> np.ndarray:
    """Distance from c along unit rays u (N, 2) to the boundary of the convex polygon p (n, 2, CCW)
    eroded by d mm: the erosion is the intersection of the edge half-planes moved inwards by d.
    Rays go in blocks of RAY_BLOCK_ENTRIES / n, so a dense outline needs no (N, n) array."""
    e = np.roll(p, -1, axis=0) - p
    n = np.column_stack([e[:, 1], -e[:, 0]]) / np.linalg.norm(e, axis=1)[:, None]   # outward normals
    h = np.einsum("ij,ij->i", n, p) - d - n @ c                 # n.(c + t u) <= h_e - d
    t = np.empty(len(u))
    step = max(1, RAY_BLOCK_ENTRIES // len(p))
    for s in range(0, len(u), step):
        nu = u[s:s + step] @ n.T                                # (block, E)
        with np.errstate(divide="ignore", invalid="ignore"):
            t[s:s + step] = np.where(nu > 1e-12, h[None] / nu, np.inf).min(axis=1)
    return t


def _check_nesting(z, rings, cents) -> list[float]:
    """Each ring strictly inside the previous one; returns the min thickness of layers 1..4 (mm).
    Raises InputError naming the layer and section where they touch or cross."""
    out = []
    names = ["epidermis", "dermis", "layer 3", "layer 4 (bone outside the section)"]
    for i in range(N_LAYERS - 1):
        gaps = np.array([_min_gap(rings[k, i], rings[k, i + 1]) for k in range(len(z))])
        k = int(np.argmin(gaps))
        if gaps[k] <= 1e-3:
            if i == 3:
                raise InputError(f"section at z={z[k]:g} mm: the bone reaches outside layer 3's inner "
                                 "boundary; use a smaller bone (bone_diameter_mm/bone_profile) or offset")
            raise InputError(f"section at z={z[k]:g} mm: {names[i]} is thicker than the section allows "
                             f"(ring {i + 1} touches ring {i}); use thinner layers or a shorter z range")
        out.append(float(gaps[k]))
    return out


def _min_gap(outer: np.ndarray, inner: np.ndarray) -> float:
    """Min distance (mm) of the points of `inner` inside the convex polygon `outer`; <= 0 if outside."""
    e = np.roll(outer, -1, axis=0) - outer
    n = np.column_stack([e[:, 1], -e[:, 0]]) / np.linalg.norm(e, axis=1)[:, None]
    dist = np.einsum("ij,ij->i", n, outer)[None] - inner @ n.T        # (M, E) >= 0 inside
    return float(dist.min())


def model_from_args(source: str | None, preset: str | None, params: ModelParams, dz_mm: float = 1.0,
                    z_range_mm: tuple | None = None, tip_width_frac: float = 0.9) -> LayeredModel:
    """The layered model from a folder/file with sections.json or a preset name. Sections are cut
    to z_range_mm, by default to the body before the rounded tip (see body_z_range). params.tip_mm
    None: a rounded tip as long as the data's (the preset's cap; the sections beyond the body)."""
    if (source is None) == (preset is None):
        raise InputError("give either a folder with sections.json or --preset (human, monkey), not both")
    if preset is not None:
        if preset not in PRESET_PARAMS:
            raise InputError(f"unknown preset '{preset}': use one of {sorted(PRESET_PARAMS)}")
        z, polys, digest = preset_sections(preset, dz_mm)
    else:
        z, polys, digest = load_sections(source)
        polys = [check_polygon(p, f"section at z={zi:g} mm") for zi, p in zip(z, polys)]
        if z_range_mm is None:
            z_range_mm = body_z_range(z, polys, tip_width_frac)
    tip_mm = params.tip_mm
    if preset is not None and tip_mm is None:
        tip_mm = float(FINGERTIP_PRESETS[preset]["cap"])              # its ellipsoidal cap
    if z_range_mm is not None:
        lo, hi = z_range_mm
        keep = (z >= lo - 1e-9) & (z <= hi + 1e-9)
        if tip_mm is None:
            tip_mm = tip_length(z, polys, int(np.flatnonzero(keep)[-1]))
        z, polys = z[keep], [p for p, k in zip(polys, keep) if k]
    return build_model(z, polys, replace(params, tip_mm=tip_mm), preset, digest)


def params_for(preset: str | None, **overrides) -> ModelParams:
    """ModelParams with the preset's defaults, then the given overrides (None values ignored)."""
    base = ModelParams(**PRESET_PARAMS.get(preset or "", {}))
    return replace(base, **{k: v for k, v in overrides.items() if v is not None})
