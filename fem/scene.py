"""The scene: indentation experiments on one model folder, as a TOML file or command-line flags.

    material = "m43338"                  # optional: material code (default: the model's)
    nu = 0.48                            # optional: Poisson ratio (default: the model's)
    [receptors]                          # optional
    depths_mm = [0.5, 0.75, 1.0]         # or "0.5:1:0.25", "0.5,1", 0.75
    spacing_mm = 1.0
    line = ["z", "middle"]               # receptors on a line only: [axis, mm or "middle"]
    measures = ["sed_MPa", ...]          # fem.measures names
    [output]                             # optional
    pvd = true                           # full fields per indentation (default: up to 20 of them)
    plots = true
    [[experiment]]                       # one or more
    name = "C5"
    indentor = "C5"                      # fem.indentors code
    orientation = "parallel"             # or "perpendicular", or an angle in degrees
    position_mm = [0.0, 5.0]             # [x, z], [x, y, z] or "top"
    incline_deg = -30                    # or approach = [0, -1, 0]; default: the model's support
    depth_mm = "0.5:3:0.5"               # or force_N = 0.02 (+ equal_force, max_depth_mm)
    sweep = "x=-3:3:0.1"                 # optional: move the indentor along x or z (mm)

Every key is declared once, below, with its type, unit and default (`Scene`, `Receptors`,
`Output`, `Experiment`); unknown keys and wrong types are one-line InputErrors.
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field

import numpy as np

from common.errors import InputError
from fem.contact import MAX_DEPTH_MM
from fem.indentors import orientation_deg, shapes_for
from fem.materials import Material
from fem.measures import check_names
from fem.receptors import DEFAULT_DEPTHS_MM, DEFAULT_MEASURES

AXES = {"x": 0, "y": 1, "z": 2}


# --------------------------------------------------------------------------- value lists
def parse_values(text) -> np.ndarray:
    """'a:b:step' (inclusive), 'v1,v2,...', a number or a list -> (n,) floats."""
    if isinstance(text, (int, float)):
        return np.array([float(text)])
    if isinstance(text, (list, tuple)):
        return np.asarray(text, float)
    try:
        if ":" in text:
            a, b, step = (float(t) for t in text.split(":"))
            if not step > 0 or b < a:
                raise ValueError
            return a + step * np.arange(int(np.floor((b - a) / step + 1e-9)) + 1)
        return np.array([float(t) for t in text.split(",")])
    except ValueError:
        raise InputError(f"bad value list '{text}': use start:stop:step (e.g. 0.5:3:0.5) or v1,v2,...") from None


def parse_sweep(text) -> tuple[int, np.ndarray]:
    """'x=-3:3:0.1' or 'z=...' -> (axis index, (k,) offsets in mm)."""
    axis, eq, values = str(text).partition("=")
    if not eq or axis.strip() not in ("x", "z"):
        raise InputError(f"bad sweep '{text}': use x=start:stop:step or z=start:stop:step (mm)")
    return {"x": 0, "z": 2}[axis.strip()], parse_values(values)


# --------------------------------------------------------------------------- key types
def _bad(key, where, want, value):
    return InputError(f"{where} {key}: expected {want}, got {value!r}")


def _number(value, key, where):
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise _bad(key, where, "a number", value)
    return float(value)


def _boolean(value, key, where):
    if not isinstance(value, bool):
        raise _bad(key, where, "true or false", value)
    return value


def _text(value, key, where):
    if not isinstance(value, str):
        raise _bad(key, where, "a string", value)
    return value


def _values(value, key, where):
    if isinstance(value, bool) or not isinstance(value, (int, float, str, list, tuple)):
        raise _bad(key, where, 'a number, a list or "start:stop:step"', value)
    try:
        return tuple(float(v) for v in parse_values(value))
    except InputError:
        raise
    except (TypeError, ValueError):
        raise _bad(key, where, "numbers", value) from None


def _names(value, key, where):
    if not isinstance(value, (list, tuple)) or not all(isinstance(v, str) for v in value):
        raise _bad(key, where, "a list of names", value)
    return tuple(value)


def _orientation(value, key, where):
    if isinstance(value, bool) or not isinstance(value, (str, int, float)):
        raise _bad(key, where, '"parallel", "perpendicular" or an angle in degrees', value)
    return value


def _position(value, key, where):
    """[x, z] or [x, y, z] in mm (kept as given: run.json records them), or "top"."""
    if isinstance(value, str):
        if value != "top":
            raise InputError(f'position_mm "{value}": give [x, z] in mm or "top"')
        return value
    if (not isinstance(value, (list, tuple)) or len(value) not in (2, 3)
            or not all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in value)):
        raise _bad(key, where, '[x, z] or [x, y, z] in mm, or "top"', value)
    return tuple(value)


def _vector3(value, key, where):
    if (not isinstance(value, (list, tuple, np.ndarray)) or len(value) != 3
            or not all(isinstance(v, (int, float, np.floating)) and not isinstance(v, bool) for v in value)):
        raise _bad(key, where, "a 3-vector [x, y, z]", value)
    return tuple(float(v) for v in value)


def _line(value, key, where):
    """[axis, value]: axis x, y or z and a number in mm or "middle" (kept as given)."""
    ok = isinstance(value, (list, tuple)) and len(value) == 2 and str(value[0]) in AXES
    if ok and value[1] != "middle":
        try:
            float(value[1])
        except (TypeError, ValueError):
            ok = False
    if not ok:
        raise InputError(f"bad receptor line {list(value) if isinstance(value, tuple) else value}: "
                         f"use z=<mm> or z=middle (3D), x=<mm>")
    return tuple(value)


def _sweep(value, key, where):
    axis, offsets = parse_sweep(value)
    _finite(offsets, key, where)
    return axis, tuple(float(v) for v in offsets)


def _finite(values, key, where, low=None, strict=False):
    """Raise InputError unless every value is finite and above `low` (strict: > low, else >= low)."""
    v = np.atleast_1d(np.asarray(values, float))
    bad = ~np.isfinite(v)
    if low is not None:
        bad |= (v <= low) if strict else (v < low)
    if not len(v) or bad.any():
        want = "finite" + ("" if low is None else f" and {'>' if strict else '>='} {low:g}")
        shown = values[0] if isinstance(values, tuple) and len(values) == 1 else values
        raise InputError(f"{where} {key} must be {want}, got {shown!r}")


def _key(unit: str, parse, default=None, doc: str = "", toml: str | None = None):
    """A scene key: its unit, parser (value, key, table) -> typed value, default and meaning."""
    factory = default if callable(default) else None
    kw = {"default_factory": factory} if factory else {"default": default}
    return field(**kw, metadata={"unit": unit, "parse": parse, "doc": doc, "toml": toml})


def _toml_name(f) -> str:
    return f.metadata.get("toml") or f.name


def _parse_table(cls, table, where: str, **given):
    """Keyword values of dataclass `cls` from a TOML table: unknown keys and wrong types are errors."""
    if not isinstance(table, dict):
        raise InputError(f"{where} must be a table")
    keys = {_toml_name(f): f for f in dataclasses.fields(cls) if f.metadata.get("parse")}
    unknown = set(table) - set(keys) - set(given)
    if unknown:
        raise InputError(f"unknown key(s) {sorted(unknown)} in {where}; allowed: {sorted(set(keys) | set(given))}")
    out = {}
    for name, f in keys.items():
        if name in table:
            out[f.name] = f.metadata["parse"](table[name], name, where)
    return out


# --------------------------------------------------------------------------- schema
@dataclass(frozen=True)
class Receptors:
    """[receptors]: where receptor points lie and what is measured there."""
    depths_mm: tuple = _key("mm", _values, lambda: tuple(DEFAULT_DEPTHS_MM), "depths below the surface")
    spacing_mm: float = _key("mm", _number, 1.0, "spacing of the receptor sites")
    line: tuple | None = _key("[axis, mm | 'middle']", _line, None, "sites on the plane x[axis] = value only")
    measures: tuple = _key("", _names, lambda: tuple(DEFAULT_MEASURES), "fem.measures names")

    @classmethod
    def from_dict(cls, table) -> Receptors:
        kw = _parse_table(cls, table, "[receptors]")
        if "depths_mm" in kw:
            _finite(kw["depths_mm"], "depths_mm", "[receptors]", 0.0)
        if "spacing_mm" in kw:
            _finite(kw["spacing_mm"], "spacing_mm", "[receptors]", 0.0, strict=True)
        if "measures" in kw:
            check_names(kw["measures"])
        return cls(**kw)


@dataclass(frozen=True)
class Output:
    """[output]: optional files of the run folder."""
    pvd: bool | None = _key("", _boolean, None, "full fields per indentation (None: up to 20 indentations)")
    plots: bool = _key("", _boolean, True, "PNG figures per experiment")

    @classmethod
    def from_dict(cls, table) -> Output:
        return cls(**_parse_table(cls, table, "[output]"))


@dataclass(frozen=True)
class Experiment:
    """[[experiment]]: one indentor, placed, at depths or a force, possibly swept."""
    name: str = _key("", _text, None, "file stem of its outputs (default experiment<k>)")
    indentor: str = _key("", _text, None, "fem.indentors code, e.g. C5, bar:1.5, step:3")
    orientation: str | float = _key("deg", _orientation, "parallel", "length axis: parallel, perpendicular or deg")
    position_mm: tuple | str | None = _key("mm", _position, None,
                                           '[x, z], [x, y, z] or "top" (None: x = 0 at the middle of the pad)')
    incline_deg: float | None = _key("deg", _number, None, "finger incline (fem.indentors.approach_direction)")
    approach: tuple | None = _key("", _vector3, None, "direction of travel (default: the model's support)")
    depth_mm: tuple | None = _key("mm", _values, None, "depths beyond first touch")
    force_N: float | None = _key("N", _number, None, "total force (N/mm in 2D); the depth is solved for")
    equal_force: bool = _key("", _boolean, False, "with force_N: every part carries force_N")
    max_depth_mm: float = _key("mm", _number, MAX_DEPTH_MM, "depth limit of force control")
    sweep: tuple | None = _key("axis=start:stop:step mm", _sweep, None, "(axis index, offsets mm) of the sweep")

    @classmethod
    def from_dict(cls, table, k: int = 0) -> Experiment:
        """The k-th (0-based) [[experiment]] table."""
        kw = _parse_table(cls, table, "[[experiment]]")
        kw.setdefault("name", f"experiment{k + 1}")
        if "indentor" not in kw:
            raise InputError(f"experiment '{kw['name']}': give its indentor (a fem.indentors code)")
        if ("depth_mm" in kw) == ("force_N" in kw):
            raise InputError(f"experiment '{kw['name']}': give depth_mm or force_N (one of them)")
        where = f"experiment '{kw['name']}'"
        shapes_for(kw["indentor"])
        orientation_deg(kw.get("orientation", "parallel"))
        for key, low, strict in (("depth_mm", 0.0, False), ("force_N", 0.0, True),
                                 ("max_depth_mm", 0.0, True), ("incline_deg", None, False)):
            if key in kw:
                _finite(kw[key], key, where, low, strict)
        return cls(**kw)

    def check_dim(self, dim: int) -> None:
        """Raise InputError for what a model of `dim` (2 or 3) cannot do: a 2D (plane-strain)
        model has its indentors along the finger axis only, and no z sweep."""
        if dim == 2 and orientation_deg(self.orientation) != 0:
            raise InputError(f"experiment '{self.name}': orientation {self.orientation!r} on a 2D model; "
                             "2D (plane-strain) indentors lie along the finger axis: use parallel")
        if dim == 2 and self.sweep is not None and self.sweep[0] == 2:
            raise InputError(f"experiment '{self.name}': a z sweep on a 2D model; sweep along x (x=start:stop:step)")

    @property
    def loads(self) -> list[dict]:
        """Keyword arguments of ContactModel.indent, one dict per indentation at each position."""
        if self.force_N is None:
            return [{"depth_mm": d} for d in self.depth_mm]
        return [{"force_N": self.force_N, "equal_force": self.equal_force, "max_depth_mm": self.max_depth_mm}]

    @property
    def offsets_mm(self) -> np.ndarray:
        """(k, 3) indentor offsets of the sweep (one zero row without a sweep)."""
        if self.sweep is None:
            return np.zeros((1, 3))
        axis, vals = self.sweep
        offsets = np.zeros((len(vals), 3))
        offsets[:, axis] = vals
        return offsets


@dataclass(frozen=True)
class Scene:
    """A scene: material overrides, receptors, outputs and the experiments, in order."""
    experiments: tuple = _key("", None, tuple, "[[experiment]] tables", toml="experiment")
    material: str | None = _key("", _text, None, "material code or moduli (default: the model's)")
    nu: float | None = _key("", _number, None, "Poisson ratio (default: the model's)")
    receptors: Receptors = _key("", lambda v, key, where: Receptors.from_dict(v), Receptors, "[receptors]")  # noqa: RUF009
    output: Output = _key("", lambda v, key, where: Output.from_dict(v), Output, "[output]")  # noqa: RUF009

    @classmethod
    def from_dict(cls, d, source: str = "scene") -> Scene:
        """A scene from its TOML tables; source names it in the error of a missing experiment."""
        kw = _parse_table(cls, d, "scene", experiment=None)
        tables = d.get("experiment")
        if not tables:
            raise InputError(f"{source} has no [[experiment]] table")
        if not isinstance(tables, list):
            raise InputError("scene experiment: expected [[experiment]] tables")
        if "material" in kw or "nu" in kw:
            Material(kw.get("material", "m33338"), kw.get("nu", 0.48))      # the code's form and nu's range
        return cls(experiments=tuple(Experiment.from_dict(t, k) for k, t in enumerate(tables)), **kw)

    def check_dim(self, dim: int) -> None:
        """Raise InputError if an experiment cannot run on a model of `dim` (`Experiment.check_dim`)."""
        for exp in self.experiments:
            exp.check_dim(dim)


def load_scene(path) -> Scene:
    """Read a TOML scene file (`Scene.from_dict`)."""
    import tomllib

    try:
        with open(path, "rb") as fh:
            d = tomllib.load(fh)
    except (OSError, ValueError) as exc:             # TOMLDecodeError, UnicodeDecodeError are ValueErrors
        raise InputError(f"cannot read scene '{path}': {' '.join(str(exc).split())}") from None
    return Scene.from_dict(d, f"scene '{path}'")
