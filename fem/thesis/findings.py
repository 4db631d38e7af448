"""What a thesis claim becomes when the project runs it: a `Finding` (the thesis's statement, the
project's number for it, the difference and a verdict with its measured reason, and the figure's
`Series`), and the `Workshop` that meshes the models the claims run on (coarse when quick) and
keeps them for resumed runs.

The claims themselves are in fem.thesis.chapter4 (chapter 4 and the appendices: plane-strain models)
and fem.thesis.chapters5_7 (chapters 5-7: the 3D presets and their sections); fem.thesis.claims lists them.
Units: mm, N (N/mm on the 2D models), MPa.
"""
from __future__ import annotations

from dataclasses import asdict, dataclass, field
from pathlib import Path

from fem.contact.linear import ContactModel
from fem.core.materials import Material
from fem.geometry import mesh2d
from fem.geometry.layered import model_from_args, params_for
from fem.geometry.mesh3d import Sizing, run_mesh
from fem.io.modelfolder import CONTACT_REGION, factorise, read_model
from fingertip.progress import as_progress

REPRODUCED, DIFFERS = "reproduced", "differs"

@dataclass
class Series:
    """One curve of a finding's figure."""
    label: str
    x: list
    y: list
    style: str = "-o"


@dataclass
class Finding:
    """A thesis statement against the project's measurement.

    key: file-name-safe id; section: thesis section and figure; thesis: the statement (number or
    trend); quantity: what `value` and `thesis_value` are (with unit); verdict: REPRODUCED or
    DIFFERS; reason: the measured explanation; series / xlabel / ylabel / logx: the figure;
    table: rows of the numbers behind it."""
    key: str
    section: str
    title: str
    thesis: str
    quantity: str
    thesis_value: float | None
    value: float | None
    verdict: str
    reason: str
    xlabel: str = ""
    ylabel: str = ""
    series: list = field(default_factory=list)
    table: list = field(default_factory=list)
    logx: bool = False

    @property
    def relative_difference(self) -> float | None:
        """(value - thesis_value) / |thesis_value|; None without both numbers."""
        if self.value is None or not self.thesis_value:
            return None
        return (self.value - self.thesis_value) / abs(self.thesis_value)

    def to_json(self) -> dict:
        return asdict(self)

    @classmethod
    def from_json(cls, data: dict) -> Finding:
        data = dict(data)
        data["series"] = [Series(**s) for s in data.get("series", [])]
        return cls(**data)


class Workshop:
    """Model folders under `root`, meshed on first use and kept for resumed runs: the 2D thesis
    models (0.25 mm elements in the top 1 mm when quick, else the thesis's 0.125 mm) and the 3D
    presets (1 mm volar elements when quick, else 0.5 mm, the thesis's surface element size)."""

    #: name -> (fem.geometry.mesh2d domain function, its arguments): the models claims ask for by name
    MODELS = {"block": ("preset_domain", ("block",), {}), "square": ("preset_domain", ("square",), {}),
              "cylinder8": ("preset_domain", ("cylinder8",), {}),
              "cylinder8_bone": ("preset_domain", ("cylinder8",), {"bone": True}),
              "cylinder8_fluid": ("preset_domain", ("cylinder8",), {"solid_fluid": True}),
              "cylinder16_bone": ("preset_domain", ("cylinder16",), {"bone": True}),
              "block_free": ("rectangle_domain", ("block_free", 40.0, 18.0), {"held_sides": False})}

    def __init__(self, root, quick: bool, progress=None):
        self.root, self.quick, self.progress = Path(root), bool(quick), as_progress(progress)

    @property
    def size_mm(self) -> float:
        return 0.25 if self.quick else 0.125

    def sizing(self, size_mm: float | None = None):
        return mesh2d.Sizing2D(size_mm=self.size_mm if size_mm is None else float(size_mm))

    def folder(self, name: str, domain=None, size_mm: float | None = None) -> Path:
        """Model folder `name` (one of MODELS, or any name with its `domain`), meshed if absent;
        size_mm: element size in the top 1 mm when not this workshop's (folder `name_<size>mm`)."""
        size = self.size_mm if size_mm is None else float(size_mm)
        out = self.root / (name if size == self.size_mm else f"{name}_{size:g}mm")
        if not (out / "model.json").is_file():
            if domain is None:
                build, args, kw = self.MODELS[name]
                domain = getattr(mesh2d, build)(*args, **kw)
            mesh2d.run_mesh2d(out, domain, self.sizing(size), progress=self.progress)
        return out

    def preset(self, preset: str, size_mm: float | None = None) -> Path:
        """3D model folder of a preset ('human' or 'monkey') with `size_mm` volar elements
        (default: 1.0 mm when quick, else 0.5 mm), meshed if absent."""
        size = (1.0 if self.quick else 0.5) if size_mm is None else float(size_mm)
        out = self.root / (f"{preset}_3d" if size == 1.0 else f"{preset}_3d_{size:g}mm")
        if not (out / "model.json").is_file():
            run_mesh(out, model_from_args(None, preset, params_for(preset)), Sizing(size_mm=size),
                     progress=self.progress)
        return out

    def contact_model(self, name: str, material="m33338", rigid_bone: bool = False):
        """(fem.contact.linear.ContactModel, Model) of model folder `name`, factorised."""
        model, info = read_model(self.folder(name), material=Material(material, rigid_bone=rigid_bone))
        return ContactModel.from_fe(model, factorise(model, info), CONTACT_REGION[model.dim]), model
