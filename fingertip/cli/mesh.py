"""`mesh`: a model folder from sections or a preset. The sizing and model-parameter flags are
derived from `fem.geometry.mesh3d.Sizing`, `fem.geometry.mesh2d.Sizing2D` and
`fem.geometry.layered.ModelParams` (`fingertip.cli.options.add_declared`)."""
from __future__ import annotations

from fem.geometry.build import SIZE_FIELDS, MeshSpec
from fem.geometry.layered import ModelParams
from fem.geometry.mesh2d import Sizing2D
from fem.geometry.mesh3d import Sizing
from fingertip.cli.options import FINITE, add_declared, declared_values, number
from fingertip.jobs.mesh import check_mesh, mesh_folder

PARAM_FLAGS = ("epidermis_mm", "dermis_mm", "layer3_mm", "layer3_scale", "bone_diameter_mm", "bone_profile",
               "bone_offset_mm", "nail_span_deg", "nail_z_frac", "support_span_deg", "support_z_frac",
               "support_incline_deg", "tip_mm")
"""The ModelParams fields the command line sets."""


def add_sizes(p) -> None:
    """--size, --coarse, --growth, --fine-depth: the sizing fields, with both dimensions' defaults."""
    defaults = {}
    for name in SIZE_FIELDS:
        d3, d2 = getattr(Sizing(), name), getattr(Sizing2D(), name)
        defaults[name] = f"{d3:g} in 3D, {d2:g} in 2D" if d3 != d2 else f"{d3:g}"
    add_declared(p, Sizing, SIZE_FIELDS, defaults=defaults)


def add_mesh(p):
    """The `mesh` command's arguments on its parser `p`."""
    p.add_argument("source", nargs="?", help="folder with sections.json (or the file itself)")
    p.add_argument("--preset", help="3D: human, monkey (parametric fingertip, no images); 2D (thesis ch. 4): "
                                    "block (40 x 18), square (8 x 8), cylinder8, cylinder16")
    p.add_argument("--out", required=True, help="output folder")
    p.add_argument("--section-z", type=FINITE, metavar="Z",
                   help="2D: mesh the five-layer cross-section of the 3D model at this z (mm) instead")
    p.add_argument("--bone", action="store_true", help="2D cylinders: add the central 2 mm bone (layer 5)")
    p.add_argument("--solid-fluid", action="store_true", help="2D cylinders: a 1 mm solid layer around an "
                   "incompressible fluid core (layer 6; thesis 4.6)")
    add_sizes(p)
    add_declared(p, ModelParams, PARAM_FLAGS, nail_z_frac={"metavar": ("LO", "HI")},
                 support_z_frac={"metavar": ("LO", "HI")})
    p.add_argument("--z-range", type=FINITE, nargs=2, metavar=("Z0", "Z1"),
                   help="use only the sections in this z range (mm)")
    p.add_argument("--tip-width-frac", type=number(0.0, high=1.0), default=0.9,
                   help="sections.json: end the model distally where the section width drops below this "
                        "fraction of the widest (then a flat cut, or domes with --tip rounded; default 0.9)")
    p.add_argument("--force", action="store_true", help="rebuild the mesh, ignoring the cache")
    p.add_argument("--quiet", action="store_true", help="no progress and no summary")
    p.set_defaults(run=_run_mesh, check=lambda args: check_mesh(args.out, mesh_spec(args)))


def mesh_spec(args) -> MeshSpec:
    """The MeshSpec of the parsed mesh arguments."""
    return MeshSpec(source=args.source, preset=args.preset, section_z_mm=args.section_z, bone=args.bone,
                    solid_fluid=args.solid_fluid, params=declared_values(args, ModelParams, PARAM_FLAGS),
                    sizes=declared_values(args, Sizing, SIZE_FIELDS), z_range_mm=args.z_range,
                    tip_width_frac=args.tip_width_frac)


def _run_mesh(args):
    text = mesh_folder(args.out, mesh_spec(args), force=args.force, progress=not args.quiet)
    if not args.quiet:
        print(text)
