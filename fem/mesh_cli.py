"""`pipeline.py mesh`: turn parsed options into model/sizing parameters, mesh, write, summarise."""
from __future__ import annotations

from dataclasses import replace

from fem.model import PRESET_PARAMS, model_from_args, params_for
from common.errors import InputError

PRESETS_2D = ("block", "square", "cylinder8", "cylinder16")


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


def model_params(args):
    """ModelParams from the CLI options (preset defaults for what is not given)."""
    preset = args.preset if args.preset in PRESET_PARAMS else None
    params = params_for(preset, epidermis_mm=args.epidermis, dermis_mm=args.dermis, layer3_mm=args.layer3,
                        layer3_scale=args.layer3_scale,
                        bone_diameter_mm=args.bone_diameter, bone_profile=parse_profile(args.bone_profile),
                        bone_offset_mm=args.bone_offset, nail_span_deg=args.nail_span,
                        nail_z_frac=_tuple(args.nail_z), support_span_deg=args.support_span,
                        support_z_frac=_tuple(args.support_z), support_incline_deg=args.support_incline)
    return replace(params, tip_mm=parse_tip(args.tip))      # None (rounded, the data's length) is a value


def parse_tip(text: str):
    """--tip: 'flat' -> 0.0, 'rounded' -> None (the data's length), a number -> that length in mm."""
    if text in ("flat", "rounded"):
        return 0.0 if text == "flat" else None
    try:
        return float(text)
    except ValueError:
        raise InputError(f"--tip '{text}': use flat, rounded or a length in mm, e.g. --tip 6.5") from None


def _tuple(v):
    return None if v is None else tuple(v)


def run_mesh_command(args) -> str:
    """Run the mesh subcommand; returns the summary text."""
    from fem import mesh2d

    two_d = args.preset in PRESETS_2D or args.section_z is not None
    if args.preset is not None and args.preset not in PRESETS_2D and args.preset not in PRESET_PARAMS:
        raise InputError(f"unknown preset '{args.preset}': use one of "
                         f"{sorted(PRESET_PARAMS) + list(PRESETS_2D)}")
    if args.bone and args.preset not in ("cylinder8", "cylinder16"):
        raise InputError("--bone is for the 2D cylinders (--preset cylinder8 or cylinder16)")
    if two_d:
        sizing = mesh2d.Sizing2D(**_given(size_mm=args.size, coarse_mm=args.coarse, growth=args.growth,
                                          fine_depth_mm=args.fine_depth))
        if args.section_z is not None:
            model = model_from_args(args.source, args.preset, model_params(args),
                                    z_range_mm=_tuple(args.z_range), tip_width_frac=args.tip_width_frac)
            domain = mesh2d.section_domain(model, args.section_z)
        else:
            if args.source is not None:
                raise InputError(f"--preset {args.preset} is a 2D model: give no sections folder")
            domain = mesh2d.preset_domain(args.preset, bone=args.bone)
        _, rep = mesh2d.run_mesh2d(args.out, domain, sizing, progress=not args.quiet)
        return mesh2d.summary(rep, args.out) + (size_note(model) if args.section_z is not None else "")
    from fem.mesh import Sizing, run_mesh, summary

    model = model_from_args(args.source, args.preset, model_params(args), z_range_mm=_tuple(args.z_range),
                            tip_width_frac=args.tip_width_frac)
    sizing = Sizing(**_given(size_mm=args.size, coarse_mm=args.coarse, growth=args.growth,
                             fine_depth_mm=args.fine_depth))
    done = run_mesh(args.out, model, sizing, force=args.force, progress=not args.quiet)
    if done is None:
        return (f"{args.out}: mesh.vtu and model.json are current for these inputs (use --force to redo)"
                + size_note(model))
    return summary(done[1], done[2], args.out) + size_note(model)


def size_note(model) -> str:
    """A summary line naming the parameters chosen by section size ('' when all were given)."""
    sd = model.derived["size_defaults"]
    if not sd["chosen"]:
        return ""
    return (f"\n  by section size (middle width {sd['middle_width_mm']:.2f} mm): "
            + ", ".join(f"{k} {v:g}" for k, v in sd["chosen"].items()) + " (flags override)")


def _given(**kw):
    return {k: v for k, v in kw.items() if v is not None}
