"""What a thesis claim becomes when the project runs it: a `Finding` (the thesis's words, quoted
with their section, and the `Check`s that judge the project's numbers against them, each with its
tolerance and its mesh uncertainty), and the `Workshop` that meshes the models the claims run on
at one `MeshLevel` and keeps them for resumed runs.

A finding's verdict and reason are computed from its checks, never stored: a check is
"reproduced" when its number lies inside the band the thesis's words give, "differs" when it lies
outside, and "within mesh uncertainty" when the band's edge is nearer than the number's mesh
uncertainty: Roache's grid convergence index of the finer of the two mesh levels the claim ran on,
SAFETY_FACTOR |fine - coarse| / (r^ORDER - 1) with r the levels' refinement ratio, and never below
the resolution of a measure counted on nodes. The claims themselves are in
fem.thesis.chapter4_* (chapter 4 and the appendices: plane-strain models) and
fem.thesis.chapters5_7 (the 3D presets and their sections); fem.thesis.claims lists them.
Units: mm, N (N/mm on the 2D models), MPa.
"""
from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path

from fem.contact.finite import FiniteContact
from fem.contact.linear import ContactModel
from fem.core.materials import Material
from fem.geometry import mesh2d
from fem.geometry.layered import model_from_args, params_for
from fem.geometry.mesh3d import Sizing, run_mesh
from fem.io.modelfolder import CONTACT_REGION, factorise, folder_info, folder_material, held_regions, read_model
from fingertip.progress import as_progress

REPRODUCED, DIFFERS, UNCERTAIN = "reproduced", "differs", "within mesh uncertainty"
SAFETY_FACTOR = 3.0
"""Roache's factor of safety for a grid convergence index from two meshes (P. J. Roache,
Verification and Validation in Computational Science and Engineering, 1998): a two-level change
understates the error of the finer level, most when both levels share a bias."""
ORDER = 1.0
"""The order of convergence assumed in the index: first, the lowest of the reported measures
(contact widths and areas step with the node spacing); the fingertip benchmark observes 2 to 7
where its changes shrink at all (docs/benchmarks.md), so first order is the cautious choice."""
VERDICTS = (REPRODUCED, UNCERTAIN, DIFFERS)

#: Check.test -> how it reads in a reason.
TESTS = {">": "above", "<": "below", "~": "within"}


def number(v: float | None, digits: int = 3) -> str:
    """A number for a reason or a table: `digits` significant figures, '-' for None, 'not measured'
    for NaN."""
    if v is None:
        return "-"
    if not math.isfinite(v):
        return "not measured"
    return f"{v:.{digits}g}"


@dataclass
class Check:
    """One number of a finding judged against the thesis's words read as a band.

    what: the quantity, in words (no numbers that change with the run); value: it, on the finer
    mesh; test: '>' (value above limit), '<' (below) or '~' (within tol of limit); unit: of value,
    limit and tol; coarse: the same number on the coarser mesh level (None where the claim ran on
    one level only); factor: the multiple of |value - coarse| taken as its mesh uncertainty
    (`uncertainty_factor` of the two levels, set by `with_coarse`); resolution: the smallest change
    the measure can show on the finer mesh (a node-counted contact area or width: the area of its
    outer ring of nodes, `fem.contact.linear.ContactModel.edge_area_mm2`; a quantity made of such
    measures: the most their resolutions move it), the floor of the uncertainty; why: where the
    band comes from, when the thesis gives no number."""
    what: str
    value: float
    test: str
    limit: float
    unit: str = ""
    tol: float = 0.0
    coarse: float | None = None
    factor: float = 1.0
    resolution: float = 0.0
    why: str = ""

    def __post_init__(self):
        if self.test not in TESTS:
            raise ValueError(f"Check.test must be one of {', '.join(TESTS)}, not {self.test!r}")
        self.value, self.limit, self.tol = float(self.value), float(self.limit), float(self.tol)
        self.factor, self.resolution = float(self.factor), float(self.resolution)

    @property
    def margin(self) -> float:
        """Signed distance of the value inside its band (negative: outside), in `unit`; NaN when
        the value is not finite."""
        if not math.isfinite(self.value):
            return math.nan
        if self.test == ">":
            return self.value - self.limit
        if self.test == "<":
            return self.limit - self.value
        return self.tol - abs(self.value - self.limit)

    @property
    def uncertainty(self) -> float:
        """The mesh uncertainty of the number on the finer mesh: factor |value - coarse|, at least
        the resolution (the resolution alone when run on one level; NaN when the coarse value is not
        finite)."""
        if self.coarse is None:
            return self.resolution
        if not math.isfinite(self.coarse):
            return math.nan
        return max(self.factor * abs(self.value - self.coarse), self.resolution)

    @property
    def outcome(self) -> str:
        """REPRODUCED inside the band by more than the uncertainty, DIFFERS outside it by more,
        UNCERTAIN between; a value that is not finite differs (it was not measured)."""
        m, u = self.margin, self.uncertainty
        if math.isnan(m):
            return DIFFERS
        if math.isnan(u) or abs(m) <= u and u > 0:
            return UNCERTAIN
        return REPRODUCED if m > 0 or (m == 0 and self.test == "~") else DIFFERS

    def band(self) -> str:
        """The band in words: 'above 1', 'within 0.5 +- 0.1 mm'."""
        u = f" {self.unit}" if self.unit else ""
        if self.test == "~":
            return f"within {number(self.limit)} +- {number(self.tol)}{u}"
        return f"{TESTS[self.test]} {number(self.limit)}{u}"

    def text(self) -> str:
        """The check as a sentence: value with its mesh uncertainty, band, outcome."""
        u = f" {self.unit}" if self.unit else ""
        parts = ([f"coarser mesh {number(self.coarse)}{u}"] if self.coarse is not None else []) + (
            [f"resolution {number(self.resolution, 2)}{u}"] if self.resolution > 0 else [])
        spread = f" ({', '.join(parts)}: mesh uncertainty {number(self.uncertainty, 2)}{u})" if parts else ""
        why = f"; {self.why}" if self.why else ""
        return f"{self.what}: {number(self.value)}{u}{spread}; judged {self.band()}{why}: {self.outcome}."


def verdict_of(checks) -> str:
    """A finding's verdict from its checks: DIFFERS if any check differs, else UNCERTAIN if any
    is within the mesh uncertainty, else REPRODUCED."""
    outcomes = {c.outcome for c in checks}
    return DIFFERS if DIFFERS in outcomes else UNCERTAIN if UNCERTAIN in outcomes else REPRODUCED


@dataclass
class Series:
    """One curve of a finding's figure; axis 1 puts it on the figure's second y axis (another
    quantity or unit)."""
    label: str
    x: list
    y: list
    style: str = "-o"
    axis: int = 0


@dataclass
class Finding:
    """A thesis statement against the project's measurement.

    key: file-name-safe id; section: the thesis section and figure; title; thesis: the thesis's
    words, quoted; checks: the judged numbers (the first is the headline of the summary table);
    notes: further measured context (computed sentences); series / xlabel / ylabel / y2label /
    logx: the figure; table: rows of the numbers behind it; reading: how the words are read, where
    they can be read more than one way (each reading is a finding of its own)."""
    key: str
    section: str
    title: str
    thesis: str
    checks: list
    notes: str = ""
    xlabel: str = ""
    ylabel: str = ""
    series: list = field(default_factory=list)
    table: list = field(default_factory=list)
    logx: bool = False
    y2label: str = ""
    reading: str = ""
    kinematics: str = "linear"

    def __post_init__(self):
        if not self.checks:
            raise ValueError(f"finding {self.key} has no check: its verdict would not be computed")

    @property
    def verdict(self) -> str:
        return verdict_of(self.checks)

    @property
    def reason(self) -> str:
        """Every check as a sentence, then the notes."""
        return " ".join([c.text() for c in self.checks] + ([self.notes] if self.notes else []))

    @property
    def headline(self) -> Check:
        return self.checks[0]

    def to_json(self) -> dict:
        """The finding's data with its computed verdict and reason alongside (read back ignores them)."""
        return {**asdict(self), "verdict": self.verdict, "reason": self.reason}

    @classmethod
    def from_json(cls, data: dict) -> Finding:
        data = {k: v for k, v in data.items() if k not in ("verdict", "reason")}
        data["series"] = [Series(**s) for s in data.get("series", [])]
        data["checks"] = [Check(**c) for c in data["checks"]]
        return cls(**data)


def with_coarse(fine: list[Finding], coarse: list[Finding], factor: float = 1.0) -> list[Finding]:
    """The findings of the finer mesh level with each check's `coarse` set from the same claim run
    on the coarser level (matched by key, then by position and `what`) and its uncertainty
    `factor` (`uncertainty_factor` of the two levels)."""
    by_key = {f.key: f for f in coarse}
    out = []
    for f in fine:
        other = by_key.get(f.key)
        if other is None or [c.what for c in other.checks] != [c.what for c in f.checks]:
            raise ValueError(f"finding {f.key}: the coarse level's checks do not match the fine level's")
        checks = [replace(c, coarse=o.value, factor=factor) for c, o in zip(f.checks, other.checks)]
        out.append(replace(f, checks=checks))
    return out


def folder_code(folder) -> str:
    """The material code a model folder records, fitted to its layers: for the 2D thesis models the
    homogeneous 1 kPa tissue with a 100 MPa bone (m3 without a bone, m33338 with one)."""
    return folder_material(folder_info(folder))[0]


@dataclass(frozen=True)
class MeshLevel:
    """Element sizes a claim runs at: 2D models (size in the top 1 mm) and 3D presets (volar), mm."""
    name: str
    size2d_mm: float
    size3d_mm: float


#: The mesh levels from coarsest to finest; a quick run uses the two coarsest, a full run the two
#: finest (the thesis's sizes, 0.125 mm in 2D and 0.5 mm on the 3D surface, and the 2D size halved).
LEVELS = (MeshLevel("0.25 mm 2D, 1.5 mm 3D", 0.25, 1.5), MeshLevel("0.125 mm 2D, 1 mm 3D", 0.125, 1.0),
          MeshLevel("0.0625 mm 2D, 0.5 mm 3D", 0.0625, 0.5))


def levels(quick: bool) -> tuple[MeshLevel, MeshLevel]:
    """(coarser, finer) mesh levels of a quick or a full run."""
    return (LEVELS[0], LEVELS[1]) if quick else (LEVELS[1], LEVELS[2])


def uncertainty_factor(coarse: MeshLevel, fine: MeshLevel) -> float:
    """SAFETY_FACTOR / (r^ORDER - 1), r the smaller of the levels' 2D and 3D size ratios: the
    multiple of a number's change between the levels taken as its mesh uncertainty (quick run:
    r = 1.5, 6; full run: r = 2, 3)."""
    r = min(coarse.size2d_mm / fine.size2d_mm, coarse.size3d_mm / fine.size3d_mm)
    return SAFETY_FACTOR / (r**ORDER - 1)


class Workshop:
    """Model folders under `root`, meshed on first use and kept for resumed runs: the 2D thesis
    models at the level's 2D size and the 3D presets at its 3D size (default: the finer level of a
    quick or full run). Folders are named by their size, so levels share what they can."""

    #: name -> (fem.geometry.mesh2d domain function, its arguments): the models claims ask for by name
    MODELS = {"block": ("preset_domain", ("block",), {}), "square": ("preset_domain", ("square",), {}),
              "cylinder8": ("preset_domain", ("cylinder8",), {}),
              "cylinder8_bone": ("preset_domain", ("cylinder8",), {"bone": True}),
              "cylinder8_fluid": ("preset_domain", ("cylinder8",), {"solid_fluid": True}),
              "cylinder16_bone": ("preset_domain", ("cylinder16",), {"bone": True}),
              "block_free": ("rectangle_domain", ("block_free", 40.0, 18.0), {"held_sides": False})}

    def __init__(self, root, quick: bool, progress=None, level: MeshLevel | None = None):
        self.root, self.quick, self.progress = Path(root), bool(quick), as_progress(progress)
        self.level = levels(quick)[1] if level is None else level

    def at(self, level: MeshLevel) -> Workshop:
        """This workshop's folders and progress at another mesh level."""
        return Workshop(self.root, self.quick, self.progress, level)

    @property
    def size_mm(self) -> float:
        """2D element size in the top 1 mm, mm."""
        return self.level.size2d_mm

    def sizing(self, size_mm: float | None = None):
        return mesh2d.Sizing2D(size_mm=self.size_mm if size_mm is None else float(size_mm))

    def folder(self, name: str, domain=None, size_mm: float | None = None) -> Path:
        """2D model folder `name` (one of MODELS, or any name with its `domain`) at `size_mm`
        (default: the level's), meshed if absent."""
        size = self.size_mm if size_mm is None else float(size_mm)
        out = self.root / f"{name}_{size:g}mm"
        if not (out / "model.json").is_file():
            if domain is None:
                build, args, kw = self.MODELS[name]
                domain = getattr(mesh2d, build)(*args, **kw)
            mesh2d.run_mesh2d(out, domain, self.sizing(size), progress=self.progress)
        return out

    def preset(self, preset: str, size_mm: float | None = None) -> Path:
        """3D model folder of a preset ('human' or 'monkey') with `size_mm` volar elements
        (default: the level's), meshed if absent."""
        size = self.level.size3d_mm if size_mm is None else float(size_mm)
        out = self.root / f"{preset}_3d_{size:g}mm"
        if not (out / "model.json").is_file():
            run_mesh(out, model_from_args(None, preset, params_for(preset)), Sizing(size_mm=size),
                     progress=self.progress)
        return out

    def _read(self, name: str, material: str | None, rigid_bone: bool):
        """(Model, model.json) of model folder `name` (meshed if absent) with `material` (default:
        the folder's code, `folder_code`)."""
        folder = self.folder(name)
        return read_model(folder, material=Material(material or folder_code(folder), rigid_bone=rigid_bone))

    def finite_contact(self, name: str, material: str | None = None, rigid_bone: bool = False):
        """(fem.contact.finite.FiniteContact, Model) of model folder `name` with large-deformation
        kinematics; material as `contact_model`'s."""
        model, _ = self._read(name, material, rigid_bone)
        return FiniteContact(model, CONTACT_REGION[model.dim], held_regions(model)), model

    def contact_model(self, name: str, material: str | None = None, rigid_bone: bool = False):
        """(fem.contact.linear.ContactModel, Model) of model folder `name`, factorised; material:
        a code (default: the folder's, `folder_code`)."""
        model, info = self._read(name, material, rigid_bone)
        return ContactModel.from_fe(model, factorise(model, info), CONTACT_REGION[model.dim]), model
