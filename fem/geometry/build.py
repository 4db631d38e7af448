"""A model folder (mesh.vtu + model.json) from what a user asks for: the layered model of a
sections.json or a 3D preset meshed with tetrahedra, a 2D preset, or a cross-section of the 3D
model meshed in plane strain (`pipeline.py mesh`, the `run` chain and `batch` all build here).

    spec = MeshSpec(preset="monkey", sizes={"size_mm": 1.0})
    spec.check()                                 # every refusal, before any file is read
    built = build_folder("out/monkey", spec)     # None fields: the preset's or the dimension's default
    built.summary

Model parameters and sizes are given as {field: value} of `fem.geometry.layered.ModelParams`
and of the dimension's sizing (`fem.geometry.mesh3d.Sizing`, `fem.geometry.mesh2d.Sizing2D`),
so each parameter is declared once, in those classes.
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field

from fem.geometry import mesh2d, mesh3d
from fem.geometry.layered import PRESET_PARAMS, ModelParams, model_from_args, params_for
from fem.geometry.presets import PRESETS_2D
from fingertip.errors import InputError

SIZE_FIELDS = ("size_mm", "coarse_mm", "growth", "fine_depth_mm")
"""Sizing fields a user may give; the 3D and the 2D sizing each declare them with their defaults."""
CYLINDERS_2D = ("cylinder8", "cylinder16")
"""The 2D presets that take a bone or a fluid core."""


@dataclass(frozen=True)
class MeshSpec:
    """What a model folder is built from. source: folder with sections.json (or the file); preset:
    3D human/monkey or a 2D preset (PRESETS_2D); section_z_mm: mesh the 2D cross-section of the 3D
    model at this z instead; bone / solid_fluid: the 2D cylinders' central bone or fluid core;
    params: given ModelParams fields; sizes: given SIZE_FIELDS; z_range_mm: (z0, z1) sections
    used; tip_width_frac: end a sections.json model where the width falls below this fraction."""
    source: str | None = None
    preset: str | None = None
    section_z_mm: float | None = None
    bone: bool = False
    solid_fluid: bool = False
    params: dict = field(default_factory=dict)
    sizes: dict = field(default_factory=dict)
    z_range_mm: tuple | None = None
    tip_width_frac: float = 0.9

    @property
    def two_d(self) -> bool:
        return self.preset in PRESETS_2D or self.section_z_mm is not None

    @property
    def sizing(self) -> mesh3d.Sizing | mesh2d.Sizing2D:
        """The sizing of the spec's dimension with the given sizes."""
        return (mesh2d.Sizing2D if self.two_d else mesh3d.Sizing)(**self.sizes)

    @property
    def model_params(self) -> ModelParams:
        """ModelParams: the preset's defaults (or those chosen by section size), then the given
        (a given None stands: tip_mm None is a rounded tip as long as the data's)."""
        base = params_for(self.preset if self.preset in PRESET_PARAMS else None)
        unknown = set(self.params) - {f.name for f in dataclasses.fields(ModelParams)}
        if unknown:
            raise InputError(f"unknown model parameter(s) {sorted(unknown)}")
        return dataclasses.replace(base, **self.params)

    def check(self) -> None:
        """Refuse what cannot be meshed, reading no file (InputError names the first problem)."""
        known = sorted(PRESET_PARAMS) + list(PRESETS_2D)
        if self.preset is not None and self.preset not in known:
            raise InputError(f"unknown preset '{self.preset}': use one of {known}")
        if self.bone and self.preset not in CYLINDERS_2D:
            raise InputError("--bone is for the 2D cylinders (--preset cylinder8 or cylinder16)")
        if self.solid_fluid and self.preset not in CYLINDERS_2D:
            raise InputError("--solid-fluid is for the 2D cylinders (--preset cylinder8 or cylinder16)")
        if self.solid_fluid and self.bone:
            raise InputError("a solid-fluid cylinder has no bone (thesis 4.6): give --bone or --solid-fluid, not both")
        if self.preset in PRESETS_2D and self.source is not None:
            raise InputError(f"--preset {self.preset} is a 2D model: give no sections folder")
        if not self.two_d and (self.source is None) == (self.preset is None):
            raise InputError("give either a folder with sections.json or --preset, not both")
        unknown = set(self.sizes) - set(SIZE_FIELDS)
        if unknown:
            raise InputError(f"unknown mesh size(s) {sorted(unknown)}; give {list(SIZE_FIELDS)}")
        self.sizing.check()
        if not self.two_d or self.section_z_mm is not None:
            self.model_params.check()

    def layered_model(self):
        """The layered model (fem.geometry.layered.LayeredModel) of a sections folder or a 3D preset."""
        return model_from_args(self.source, self.preset, self.model_params, z_range_mm=_tuple(self.z_range_mm),
                               tip_width_frac=self.tip_width_frac)


@dataclass
class BuiltFolder:
    """What `build_folder` did: summary (text), warnings (lines), current (True when the folder
    already held the outputs of these inputs and nothing was written)."""
    summary: str
    warnings: list = field(default_factory=list)
    current: bool = False


def build_folder(out, spec: MeshSpec, force: bool = False, progress=None) -> BuiltFolder:
    """Write mesh.vtu and model.json of `spec` into `out` (a current 3D folder is kept unless
    force). progress: a `fingertip.progress` object (None: silent)."""
    spec.check()
    if spec.two_d:
        if spec.section_z_mm is not None:
            model = spec.layered_model()
            domain = mesh2d.section_domain(model, spec.section_z_mm)
        else:
            model, domain = None, mesh2d.preset_domain(spec.preset, bone=spec.bone, solid_fluid=spec.solid_fluid)
        _, rep = mesh2d.run_mesh2d(out, domain, spec.sizing, progress=progress)
        return BuiltFolder(mesh2d.summary(rep, out) + (size_note(model) if model is not None else ""))
    model = spec.layered_model()
    done = mesh3d.run_mesh(out, model, spec.sizing, force=force, progress=progress)
    if done is None:
        return BuiltFolder(f"{out}: mesh.vtu and model.json are current for these inputs (use --force to redo)"
                           + size_note(model), current=True)
    return BuiltFolder(mesh3d.summary(done[1], done[2], out) + size_note(model), list(done[2]["warnings"]))


def size_note(model) -> str:
    """A summary line naming the parameters chosen by section size ('' when all were given)."""
    sd = model.derived["size_defaults"]
    if not sd["chosen"]:
        return ""
    return (f"\n  by section size (middle width {sd['middle_width_mm']:.2f} mm): "
            + ", ".join(f"{k} {v:g}" for k, v in sd["chosen"].items()) + " (flags override)")


def _tuple(v):
    return None if v is None else tuple(v)
