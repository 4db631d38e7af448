"""Back end of `pipeline.py mesh`: option values -> layered-model and sizing parameters, the 3D
tetrahedral mesh (fem.geometry.mesh3d) or the 2D plane-strain mesh (fem.geometry.mesh2d: the 2D presets, or a cross
section of the 3D model), written to the output folder; returns the summary text."""
from __future__ import annotations

import sys
from dataclasses import dataclass, replace

from fingertip.errors import InputError
from fingertip.staging import check_output_dir
from fem.geometry.layered import PRESET_PARAMS, model_from_args, params_for
from fem.geometry.presets import PRESETS_2D


@dataclass(frozen=True)
class ModelOptions:
    """Layered-model options (None: the preset's default, or the one chosen by section size)."""
    epidermis_mm: float | None = None
    dermis_mm: float | None = None
    layer3_mm: float | None = None
    layer3_scale: float | None = None
    bone_diameter_mm: float | None = None
    bone_profile: str | None = None             # 's:ratio,...', see parse_profile
    bone_offset_mm: float | None = None
    nail_span_deg: float | None = None
    nail_z_frac: tuple | None = None            # (lo, hi) fractions of the length
    support_span_deg: float | None = None
    support_z_frac: tuple | None = None
    support_incline_deg: float | None = None
    tip: str = "flat"                           # see parse_tip


def parse_profile(text: str | None):
    """'s:ratio,s:ratio,...' -> ((s, ratio), ...) or None."""
    if text is None:
        return None
    try:
        rows = tuple(tuple(float(v) for v in item.split(":")) for item in text.split(","))
    except ValueError:
        raise InputError(f"--bone-profile '{text}': expected 's:ratio,...' numbers, e.g. 0:0.25,1:0.18") from None
    if any(len(r) != 2 for r in rows):
        raise InputError(f"--bone-profile '{text}': each item is s:ratio, e.g. 0:0.25,1:0.18")
    return rows


def parse_tip(text: str):
    """--tip: 'flat' -> 0.0, 'rounded' -> None (the data's length), a number -> that length in mm."""
    if text in ("flat", "rounded"):
        return 0.0 if text == "flat" else None
    try:
        return float(text)
    except ValueError:
        raise InputError(f"--tip '{text}': use flat, rounded or a length in mm, e.g. --tip 6.5") from None


def model_params(preset: str | None, options: ModelOptions):
    """fem.geometry.layered.ModelParams from the options (the preset's defaults for what is not given)."""
    o = options
    params = params_for(preset if preset in PRESET_PARAMS else None, epidermis_mm=o.epidermis_mm,
                        dermis_mm=o.dermis_mm, layer3_mm=o.layer3_mm, layer3_scale=o.layer3_scale,
                        bone_diameter_mm=o.bone_diameter_mm, bone_profile=parse_profile(o.bone_profile),
                        bone_offset_mm=o.bone_offset_mm, nail_span_deg=o.nail_span_deg,
                        nail_z_frac=_tuple(o.nail_z_frac), support_span_deg=o.support_span_deg,
                        support_z_frac=_tuple(o.support_z_frac), support_incline_deg=o.support_incline_deg)
    return replace(params, tip_mm=parse_tip(o.tip))      # None (rounded, the data's length) is a value


def size_note(model) -> str:
    """A summary line naming the parameters chosen by section size ('' when all were given)."""
    sd = model.derived["size_defaults"]
    if not sd["chosen"]:
        return ""
    return (f"\n  by section size (middle width {sd['middle_width_mm']:.2f} mm): "
            + ", ".join(f"{k} {v:g}" for k, v in sd["chosen"].items()) + " (flags override)")


def _tuple(v):
    return None if v is None else tuple(v)


def _given(**kw):
    return {k: v for k, v in kw.items() if v is not None}


def check_options(out, source=None, preset=None, section_z_mm=None, bone=False, solid_fluid=False, size_mm=None, coarse_mm=None,
                  growth=None, fine_depth_mm=None, options: ModelOptions = ModelOptions()):
    """Validate `run_mesh`'s options without reading any file: (2D?, fem.geometry.mesh3d.Sizing or
    fem.geometry.mesh2d.Sizing2D). InputError names the first bad one."""
    from fem.geometry import mesh3d as mesh
    from fem.geometry import mesh2d

    if preset is not None and preset not in PRESETS_2D and preset not in PRESET_PARAMS:
        raise InputError(f"unknown preset '{preset}': use one of "
                         f"{sorted(PRESET_PARAMS) + list(PRESETS_2D)}")
    if bone and preset not in ("cylinder8", "cylinder16"):
        raise InputError("--bone is for the 2D cylinders (--preset cylinder8 or cylinder16)")
    if solid_fluid and preset not in ("cylinder8", "cylinder16"):
        raise InputError("--solid-fluid is for the 2D cylinders (--preset cylinder8 or cylinder16)")
    if solid_fluid and bone:
        raise InputError("a solid-fluid cylinder has no bone (thesis 4.6): give --bone or --solid-fluid, not both")
    two_d = preset in PRESETS_2D or section_z_mm is not None
    if preset in PRESETS_2D and source is not None:
        raise InputError(f"--preset {preset} is a 2D model: give no sections folder")
    if not two_d and (source is None) == (preset is None):
        raise InputError("give either a folder with sections.json or --preset, not both")
    sizes = _given(size_mm=size_mm, coarse_mm=coarse_mm, growth=growth, fine_depth_mm=fine_depth_mm)
    sizing = (mesh2d.Sizing2D if two_d else mesh.Sizing)(**sizes)
    sizing.check()
    if not two_d or section_z_mm is not None:
        model_params(preset, options).check()
    check_output_dir(out)
    return two_d, sizing


def run_mesh(out, source=None, preset=None, section_z_mm=None, bone=False, solid_fluid=False, size_mm=None, coarse_mm=None,
             growth=None, fine_depth_mm=None, options: ModelOptions = ModelOptions(), z_range_mm=None,
             tip_width_frac: float = 0.9, force=False, progress=True) -> str:
    """`pipeline.py mesh`: mesh.vtu and model.json in `out`; returns the summary text.

    source: folder with sections.json (or the file); preset: 3D 'human'/'monkey' or a 2D preset
    (PRESETS_2D); section_z_mm: mesh the 2D cross-section of the 3D model at this z instead; bone:
    the 2D cylinders' central bone; solid_fluid: their fluid core inside 1 mm of solid; size_mm, coarse_mm, growth, fine_depth_mm: mesh sizing (None:
    the defaults); z_range_mm: (z0, z1) sections used; force: rebuild a current 3D mesh."""
    from fem.geometry import mesh2d

    two_d, sizing = check_options(out, source, preset, section_z_mm, bone, solid_fluid, size_mm, coarse_mm, growth,
                                  fine_depth_mm, options)
    if two_d:
        if section_z_mm is not None:
            model = model_from_args(source, preset, model_params(preset, options),
                                    z_range_mm=_tuple(z_range_mm), tip_width_frac=tip_width_frac)
            domain = mesh2d.section_domain(model, section_z_mm)
        else:
            domain = mesh2d.preset_domain(preset, bone=bone, solid_fluid=solid_fluid)
        _, rep = mesh2d.run_mesh2d(out, domain, sizing, progress=progress)
        return mesh2d.summary(rep, out) + (size_note(model) if section_z_mm is not None else "")
    from fem.geometry import mesh3d

    model = model_from_args(source, preset, model_params(preset, options), z_range_mm=_tuple(z_range_mm),
                            tip_width_frac=tip_width_frac)
    done = mesh3d.run_mesh(out, model, sizing, force=force, progress=progress)
    for warning in () if done is None else done[2]["warnings"]:
        print(f"warning: {warning}", file=sys.stderr)
    if done is None:
        return (f"{out}: mesh.vtu and model.json are current for these inputs (use --force to redo)"
                + size_note(model))
    return mesh3d.summary(done[1], done[2], out) + size_note(model)
