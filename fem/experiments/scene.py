"""The scene: indentation experiments on one model folder, as a TOML file or command-line flags.

    material = "m43338"                  # optional: material code or [E1, E2, ...] MPa (default: the model's)
    nu = 0.48                            # optional: Poisson ratio (default: the model's)
    [viscoelastic]                       # optional: every layer relaxes (fem.core.viscoelastic)
    g = [0.2, 0.2, 0.2]                  # weights of the Prony terms (required: from your measurement)
    tau_s = [0.004, 0.07, 1.4]           # relaxation times, s (default: Pawluk and Howe 1999)
    [receptors]                          # optional
    depths_mm = [0.5, 0.75, 1.0]         # or "0.5:1:0.25", "0.5,1", 0.75
    spacing_mm = 1.0
    line = ["z", "middle"]               # receptors on a line only: [axis, mm or "middle"]
    measures = ["sed_MPa", ...]          # fem.core.measures names
    [output]                             # optional
    pvd = true                           # full fields per indentation (default false: they factorise)
    plots = true
    [[experiment]]                       # one or more
    name = "C5"
    indentor = "C5"                      # fem.contact.indentors code
    orientation = "parallel"             # or "perpendicular", or an angle in degrees
    position_mm = [0.0, 5.0]             # [x, z], [x, y, z] or "top"
    incline_deg = -30                    # or approach = [0, -1, 0]; default: the model's support
    depth_mm = "0.5:3:0.5"               # or force_N = 0.02 (+ equal_force, max_depth_mm)
    sweep = "x=-3:3:0.1"                 # optional: move the indentor along x or z (mm)
    [experiment.trace]                   # optional: a time course of the depth (or force)
    shape = "ramp_hold"                  # ramp_hold, sine, steps, table, scan (fem.experiments.traces)
    ramp_s = 0.1
    hold_s = 0.5
    release_s = 0.1
    samples = 100
    [afferents]                          # optional, with traced experiments: spiking afferents
    classes = ["SA1", "RA"]              # fem.receptors.transduction classes
    seed = 0

Every key is declared once, below, with its type, unit and default (`Scene`, `Receptors`,
`Output`, `Experiment`); unknown keys and wrong types are one-line InputErrors.
"""
from __future__ import annotations

import dataclasses
import tomllib
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from fem.contact.indentors import orientation_deg, shapes_for
from fem.contact.linear import MAX_DEPTH_MM
from fem.contact.surfaces import check_modelled
from fem.core.materials import DEFAULT_CODE, DEFAULT_NU, Material
from fem.core.measures import check_names
from fem.core.viscoelastic import PAWLUK_HOWE_TAU_S, LayerLaws, Prony
from fem.experiments.traces import check, fractions
from fem.experiments.values import parse_sweep, parse_values
from fem.io.nwb import check_available
from fem.receptors.grid import DEFAULT_DEPTHS_MM, DEFAULT_MEASURES
from fem.receptors.transduction import class_data
from fingertip.declare import declared, finite, nonnegative, positive
from fingertip.errors import InputError
from fingertip.resources import scene_names, shipped_scene

AXES = {"x": 0, "y": 1, "z": 2}


# --------------------------------------------------------------------------- bounds
MAX_INDENTATIONS = 10_000
"""Default bound on the indentations of one scene (`Scene.max_indentations`)."""
MAX_RECEPTOR_DEPTHS = 100
"""Most receptor depths a grid may have (each multiplies the receptor points)."""


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


def _material(value, key, where):
    """A material code ("m43338") or Young's moduli per layer [MPa] (a list, layers 1, 2, ...)."""
    if isinstance(value, str):
        return value
    if (isinstance(value, (list, tuple)) and value
            and all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in value)):
        return tuple(float(v) for v in value)
    raise _bad(key, where, 'a material code ("m43338") or moduli per layer in MPa ([0.01, 0.001, ...])', value)


def _whole(word: str, name: str) -> int:
    """A whole number >= 1 from a command-line word (ValueError otherwise)."""
    try:
        value = int(word)
    except ValueError:
        raise ValueError(f"must be a whole number >= 1, got {word}") from None
    if value < 1:
        raise ValueError(f"must be a whole number >= 1, got {word}")
    return value


def _count(value, key, where):
    if isinstance(value, bool) or not isinstance(value, int):
        raise _bad(key, where, "a whole number", value)
    return value


def _densities(value, key, where):
    if not isinstance(value, dict) or not all(isinstance(v, (int, float)) and not isinstance(v, bool)
                                              for v in value.values()):
        raise _bad(key, where, "a table of class = afferents per cm^2, e.g. {SA1 = 70, RA = 140}", value)
    return tuple((str(k), float(v)) for k, v in value.items())


def _points(value, key, where):
    """A list of points [[x, y, z], ...] in mm."""
    ok = (isinstance(value, (list, tuple)) and value
          and all(isinstance(v, (list, tuple)) and len(v) == 3
                  and all(isinstance(c, (int, float)) and not isinstance(c, bool) and np.isfinite(c) for c in v)
                  for v in value))
    if not ok:
        raise _bad(key, where, "a list of points [[x, y, z], ...] in mm", value)
    return tuple(tuple(float(c) for c in v) for v in value)


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


def _position_words(words: list[str]):
    """A position from command-line words: "top", or X Z in mm."""
    if words == ["top"]:
        return "top"
    try:
        x, z = (float(w) for w in words)
    except ValueError:
        raise InputError(f"--position {' '.join(words)}: give X Z in mm or top") from None
    return (x, z)


def _vector3(value, key, where):
    if (not isinstance(value, (list, tuple, np.ndarray)) or len(value) != 3
            or not all(isinstance(v, (int, float, np.floating)) and not isinstance(v, bool) for v in value)):
        raise _bad(key, where, "a 3-vector [x, y, z]", value)
    return tuple(float(v) for v in value)


def line_text(value) -> str:
    """A receptor line [axis, value] in words, as the command line writes it ("z=middle")."""
    if isinstance(value, (list, tuple)) and len(value) == 2:
        return f"{value[0]}={value[1]}"
    return repr(value)


def _line(value, key, where):
    """[axis, value]: axis x, y or z and a number in mm or "middle" (kept as given)."""
    ok = isinstance(value, (list, tuple)) and len(value) == 2 and str(value[0]) in AXES
    if ok and value[1] != "middle":
        try:
            float(value[1])
        except (TypeError, ValueError):
            ok = False
    if not ok:
        raise InputError(f"bad receptor line {line_text(value)}: "
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
        shown = ", ".join(f"{x:g}" for x in v[bad][:5]) if len(v) else "no value"
        raise InputError(f"{where} {key} must be {want}, got {shown}")


def _key(unit: str, parse, default=None, doc: str = "", toml: str | None = None, **cli):
    """A scene key (`fingertip.declare.declared`): its unit, TOML parser (value, key, table) ->
    typed value, default (a callable: a factory) and meaning; cli: how the command line reads it
    (text, flag, default_text)."""
    factory = default if callable(default) else None
    return declared(None if factory else default, unit, doc, factory=factory, parse=parse, toml=toml, **cli)


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
    depths_mm: tuple = _key("mm", _values, lambda: tuple(DEFAULT_DEPTHS_MM), "receptor depths below the surface",
                            text=str, flag="--receptor-depths")
    spacing_mm: float = _key("mm", _number, 1.0, "spacing of the receptor sites", text=positive,
                             flag="--receptor-spacing")
    line: tuple | None = _key("[axis, mm | 'middle']", _line, None,
                              "receptors only on the plane x[axis] = value: z=<mm>, z=middle or x=<mm>",
                              text=lambda word: list(word.partition("=")[::2]), default_text="the whole pad")
    measures: tuple = _key("", _names, lambda: tuple(DEFAULT_MEASURES), "fem.core.measures names")

    @classmethod
    def from_dict(cls, table) -> Receptors:
        kw = _parse_table(cls, table, "[receptors]")
        if "depths_mm" in kw:
            _finite(kw["depths_mm"], "depths_mm", "[receptors]", 0.0)
            if len(kw["depths_mm"]) > MAX_RECEPTOR_DEPTHS:
                raise InputError(f"[receptors] depths_mm: {len(kw['depths_mm'])} depths, more than the "
                                 f"{MAX_RECEPTOR_DEPTHS} a receptor grid may have: use a larger step")
        if "spacing_mm" in kw:
            _finite(kw["spacing_mm"], "spacing_mm", "[receptors]", 0.0, strict=True)
        if "measures" in kw:
            check_names(kw["measures"])
        return cls(**kw)


@dataclass(frozen=True)
class Output:
    """[output]: optional files of the run folder."""
    pvd: bool = _key("", _boolean, False, "full fields per indentation as a PVD series (factorises the model)")
    plots: bool = _key("", _boolean, True, "PNG figures per experiment")

    @classmethod
    def from_dict(cls, table) -> Output:
        return cls(**_parse_table(cls, table, "[output]"))


@dataclass(frozen=True)
class Trace:
    """[experiment.trace]: the time course of an experiment's depth (or force), as fractions of it
    over time (`fem.experiments.traces.fractions`); each sample is one quasi-static indentation."""
    shape: str = _key("", _text, "ramp_hold", "ramp_hold, sine, steps, table or scan")
    samples: int = _key("", _count, 100, "sample times (sine, ramp_hold, steps, table)")
    ramp_s: float = _key("s", _number, 0.1, "ramp time (ramp_hold, steps)")
    hold_s: float = _key("s", _number, 0.5, "hold time (ramp_hold, steps: per level)")
    release_s: float = _key("s", _number, 0.1, "release time (ramp_hold)")
    rest_s: float = _key("s", _number, 0.0, "time at rest after the release (ramp_hold)")
    frequency_hz: float = _key("Hz", _number, 0.0, "sine frequency (at most fem.experiments.traces.MAX_FREQUENCY_HZ)")
    cycles: float = _key("", _number, 1.0, "sine periods")
    offset: float = _key("", _number, 0.0, "fraction held under the sine from t = 0 (a pre-indentation; sine)")
    levels: tuple = _key("", _values, tuple, "fractions of the depth (steps, table)")
    times_s: tuple = _key("s", _values, tuple, "sample times of the levels (table)")
    speed_mm_s: float = _key("mm/s", _number, 0.0, "speed along the sweep (scan)")

    @classmethod
    def from_dict(cls, table, where: str) -> Trace:

        trace = cls(**_parse_table(cls, table, f"{where} trace"))
        check(trace, where)
        return trace


@dataclass(frozen=True)
class Afferents:
    """[afferents]: spiking afferents over the pad (fem.receptors.afferents), driven by the traced experiments."""
    classes: tuple = _key("", _names, lambda: ("SA1", "RA"), "afferent classes (fem.receptors.transduction.CLASSES)")
    density_per_cm2: tuple | None = _key("1/cm^2", _densities, None,
                                         "per class (default: the fingertip densities of fem.receptors.transduction)")
    radius_mm: float | None = _key("mm", _number, None, "only sites this close to where the first traced "
                                                       "experiment touches first (default: the whole pad)")
    input: str = _key("", _text, "stress", "stress (normal stress at the afferent, compression +) or sed")
    gain: float = _key("", _number, 1.0, "factor on the input (the published parameters are fit to stress in MPa)")
    noisy: bool = _key("", _boolean, True, "membrane noise of the published model (seeded)")
    seed: int = _key("", _count, 0, "seed of the placement and the noise")
    sites_mm: tuple | None = _key("mm", _points, None, "one afferent of each class at each of these points "
                                                       "(projected onto the pad) instead of by density")
    nwb: bool = _key("", _boolean, False, "also write <experiment>/spikes.nwb (Neurodata Without Borders; "
                                          "the nwb extra, fem.io.nwb)")

    @classmethod
    def from_dict(cls, table) -> Afferents:

        kw = _parse_table(cls, table, "[afferents]")
        for name in kw.get("classes", ()):
            class_data(name)
        for name, dens in kw.get("density_per_cm2") or ():
            if name not in kw.get("classes", ("SA1", "RA")):
                raise InputError(f"[afferents] density_per_cm2 names {name}, not one of the classes")
            _finite(dens, f"density_per_cm2 {name}", "[afferents]", 0.0, strict=True)
        if kw.get("input", "stress") not in ("stress", "sed"):
            raise InputError(f"[afferents] input must be stress or sed, got {kw['input']!r}")
        if "radius_mm" in kw:
            _finite(kw["radius_mm"], "radius_mm", "[afferents]", 0.0, strict=True)
        if "gain" in kw:
            _finite(kw["gain"], "gain", "[afferents]", 0.0, strict=True)
        if kw.get("nwb"):
            check_available()
        if "sites_mm" in kw and ("density_per_cm2" in kw or "radius_mm" in kw):
            raise InputError("[afferents] sites_mm places the afferents itself: drop density_per_cm2 and radius_mm")
        return cls(**kw)


@dataclass(frozen=True)
class Viscoelastic:
    """[viscoelastic]: the layers' moduli relax by a Prony series (fem.core.viscoelastic.Prony), one
    for every layer or, with `layers`, one per layer (fem.core.viscoelastic.LayerLaws)."""
    g: tuple = _key("", _values, None, "weights of the terms (> 0, sum < 1; 1 - sum: the relaxed fraction); "
                    "required: no published fingerpad weights are built in")
    tau_s: tuple = _key("s", _values, lambda: PAWLUK_HOWE_TAU_S, "relaxation times (distinct, > 0)")
    layers: tuple = _key("", lambda v, k, w: _layer_laws(v, k, w), tuple,
                         'per layer: {g = [...], tau_s = [...]} or "elastic" (default: g and tau_s above)')

    @classmethod
    def law(cls, value, key, where) -> Prony | LayerLaws | None:
        """The law of a scene's [viscoelastic] table (g required, tau_s optional; with layers, a
        LayerLaws whose unnamed layers take g and tau_s)."""
        if not isinstance(value, dict):
            raise _bad(key, where, "a [viscoelastic] table with the weights g (and tau_s)", value)
        kw = _parse_table(cls, value, "[viscoelastic]")
        if kw.get("g") is None:
            raise InputError(f"{where}: [viscoelastic] needs the weights g of its relaxation times tau_s "
                             f"(default {list(PAWLUK_HOWE_TAU_S)} s), e.g. g = [0.2, 0.2, 0.2] from your "
                             "relaxation measurement; no published fingerpad weights are built in")
        layers = kw.pop("layers", ())
        default = Prony(**kw)
        return LayerLaws(default, layers) if layers else default


def _layer_laws(value, key, where) -> tuple:
    """((layer, Prony or None), ...) from {layer = {g = [...], tau_s = [...]} or "elastic"}."""
    if not isinstance(value, dict) or not value:
        raise _bad(key, where, 'a table of layer = {g = [...], tau_s = [...]} or "elastic", e.g. '
                               '{1 = {g = [0.3], tau_s = [0.05]}, 5 = "elastic"}', value)
    out = []
    for name, spec in value.items():
        if not str(name).isdigit() or int(name) < 1:
            raise InputError(f"[viscoelastic] layers: {name!r} is not a layer number (1 = the epidermis, ...)")
        if spec == "elastic":
            out.append((int(name), None))
            continue
        kw = _parse_table(Viscoelastic, spec, f"[viscoelastic] layers {name}")
        if kw.get("g") is None or "layers" in kw:
            raise InputError(f'[viscoelastic] layers {name}: give its weights g (and tau_s), or "elastic"')
        out.append((int(name), Prony(**kw)))
    return tuple(sorted(out))


@dataclass(frozen=True)
class Experiment:
    """[[experiment]]: one indentor, placed, at depths or a force, possibly swept."""
    name: str = _key("", _text, None, "file stem of its outputs (default experiment<k>)")
    indentor: str = _key("", _text, None, "indentor code: C1-C8, R1-R2, cylinder:<d>, step:0-5, bar:<w>, "
                         "grating:<bar>[:<gaps>], wedge, cone, punch, plate, sphere:<r>, ellipsoid:<a,b,c>, "
                         "two-point:<separation> (fem.contact.indentors)", text=str)
    orientation: str | float = _key("deg", _orientation, "parallel", "indentor length axis: parallel or perpendicular "
                                    "to the finger axis, or an angle in degrees (2D models need parallel)",
                                    text=str, flag=("--axis", "--orientation"))
    position_mm: tuple | str | None = _key("mm", _position, None, "indentor position on the pad: [x, z], [x, y, z] "
                                           'or "top", the pad point highest against the approach',
                                           words=_position_words, nargs="+",
                                           default_text="x = 0 at the middle of the pad")
    incline_deg: float | None = _key("deg", _number, None, "finger incline (fem.contact.indentors.approach_direction)",
                                     text=finite, default_text="the model's support")
    approach: tuple | None = _key("", _vector3, None, "direction of travel (default: the model's support)")
    depth_mm: tuple | None = _key("mm", _values, None, "depths beyond first touch: start:stop:step or a list "
                                  "(e.g. 0:3:0.5)", text=str)
    force_N: float | None = _key("N", _number, None, "total force (N/mm in 2D); the depth is solved for",
                                 text=positive)
    equal_force: bool = _key("", _boolean, False, "with a force: every part of a two-point indentor carries it")
    max_depth_mm: float | None = _key("mm", _number, None, "depth limit of force control", text=positive,
                                      default_text=f"the tissue over the bone, at most {MAX_DEPTH_MM:g}")
    sweep: tuple | None = _key("mm", _sweep, None, "move the indentor: x=start:stop:step or z=start:stop:step",
                               text=str)
    trace: Trace | None = _key("", None, None, "[experiment.trace]: time course of the depth or force")  # noqa: RUF009

    @classmethod
    def from_dict(cls, table, k: int = 0) -> Experiment:
        """The k-th (0-based) [[experiment]] table."""
        kw = _parse_table(cls, table, "[[experiment]]", trace=None)
        kw.setdefault("name", f"experiment{k + 1}")
        if "indentor" not in kw:
            raise InputError(f"experiment '{kw['name']}': give its indentor (a fem.contact.indentors code)")
        if ("depth_mm" in kw) == ("force_N" in kw):
            raise InputError(f"experiment '{kw['name']}': give depth_mm or force_N (one of them)")
        where = f"experiment '{kw['name']}'"
        shapes_for(kw["indentor"])
        orientation_deg(kw.get("orientation", "parallel"))
        for key, low, strict in (("depth_mm", 0.0, False), ("force_N", 0.0, True),
                                 ("max_depth_mm", 0.0, True), ("incline_deg", None, False)):
            if key in kw:
                _finite(kw[key], key, where, low, strict)
        if "trace" in table:
            kw["trace"] = Trace.from_dict(table["trace"], where)
            if len(kw.get("depth_mm") or (0,)) != 1:
                raise InputError(f"{where}: a traced experiment takes one depth_mm (its full depth), "
                                 f"got {', '.join(f'{d:g}' for d in kw['depth_mm'])}")
            if (kw["trace"].shape == "scan") != ("sweep" in kw):
                raise InputError(f'{where}: a "scan" trace needs a sweep, and a sweep with a trace '
                                 f'needs shape = "scan"')
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
        limit = MAX_DEPTH_MM if self.max_depth_mm is None else self.max_depth_mm
        return [{"force_N": self.force_N, "equal_force": self.equal_force, "max_depth_mm": limit}]

    @property
    def indentations(self) -> list[tuple[np.ndarray, dict]]:
        """[(offset (3,) mm, keyword arguments of ContactModel.indent)] in order: every offset at
        every load, or one per sample time of the trace (a zero fraction: depth 0)."""
        if self.trace is None:
            return [(off, load) for off in self.offsets_mm for load in self.loads]
        _, offsets, frac = self._samples()
        full = self.loads[0]

        def load(f):
            if f <= 0:
                return {"depth_mm": 0.0}
            if self.force_N is None:
                return {"depth_mm": float(f * full["depth_mm"])}
            return {**full, "force_N": float(f * full["force_N"])}
        return [(off, load(f)) for off, f in zip(offsets, frac)]

    @property
    def times_s(self) -> np.ndarray | None:
        """(n,) sample times of the trace [s] (None without one), one per `indentations` entry."""
        return None if self.trace is None else self._samples()[0]

    def _samples(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(times (n,) s, offsets (n, 3) mm, fractions (n,)) of the trace's sample times."""
        sweep = self.offsets_mm if self.sweep is not None else None
        times, frac = fractions(self.trace, sweep)
        return times, (sweep if sweep is not None else np.zeros((len(frac), 3))), frac

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
    material: str | tuple | None = _key("", _material, None, "material code mABCDE (digit k: log10 of layer k's "
                                        "modulus in Pa), or moduli per layer in MPa", text=str,
                                        default_text="the model's")
    nu: float | None = _key("", _number, None, "Poisson ratio", text=nonnegative, default_text="the model's")
    viscoelastic: Prony | LayerLaws | None = _key(  # noqa: RUF009
        "", Viscoelastic.law, None, "[viscoelastic] table: every layer relaxes (traced experiments only)",
        default_text="elastic")
    receptors: Receptors = _key("", lambda v, key, where: Receptors.from_dict(v), Receptors, "[receptors]")  # noqa: RUF009
    output: Output = _key("", lambda v, key, where: Output.from_dict(v), Output, "[output]")  # noqa: RUF009
    afferents: Afferents | None = _key("", lambda v, key, where: Afferents.from_dict(v), None, "[afferents]")  # noqa: RUF009
    max_indentations: int = _key("", _count, MAX_INDENTATIONS, "most indentations the scene may run (all its "
                                 "experiments together)", text=lambda word: _whole(word, "max_indentations"))
    kinematics: str = _key("", _text, "linear", "linear (small strain) or finite (large deformation: neo-Hookean "
                           "layers; cylinders, spheres, bars, plates, punches, gratings, steps and two-point with spherical "
                           "tips, by depth or force, swept or not; "
                           "fem.contact.finite)", text=str)

    @classmethod
    def from_dict(cls, d, source: str = "scene", max_indentations: int | None = None) -> Scene:
        """A scene from its TOML tables; source names it in the error of a missing experiment;
        max_indentations: the bound on its indentations, instead of the scene's own (a flag)."""
        kw = _parse_table(cls, d, "scene", experiment=None)
        if max_indentations is not None:
            kw["max_indentations"] = max_indentations
        if kw.get("max_indentations", 1) < 1:
            raise InputError(f"{source} max_indentations must be a whole number >= 1, got {kw['max_indentations']}")
        tables = d.get("experiment")
        if not tables:
            raise InputError(f"{source} has no [[experiment]] table")
        if not isinstance(tables, list):
            raise InputError("scene experiment: expected [[experiment]] tables")
        if "material" in kw or "nu" in kw:
            Material(kw.get("material", DEFAULT_CODE), kw.get("nu", DEFAULT_NU))      # the code's form and nu's range
        experiments = tuple(Experiment.from_dict(t, k) for k, t in enumerate(tables))
        if kw.get("afferents") is not None and not any(e.trace is not None for e in experiments):
            raise InputError(f"{source}: [afferents] spike over time; give an experiment a time course "
                             f"([experiment.trace], e.g. shape = \"ramp_hold\")")
        if kw.get("viscoelastic") is not None:
            _check_viscoelastic(source, experiments, kw.get("afferents"))
        scene = cls(experiments=experiments, **kw)
        scene.check_count()
        scene.check_kinematics()
        return scene

    @property
    def indentations(self) -> int:
        """Indentations the scene runs, all experiments together."""
        return sum(len(e.indentations) for e in self.experiments)

    def check_count(self) -> None:
        """Raise InputError when the scene runs more than max_indentations indentations."""
        n = self.indentations
        if n > self.max_indentations:
            raise InputError(f"the scene asks for {n} indentations, more than max_indentations "
                             f"{self.max_indentations}: use fewer depths or sweep positions (a larger step), "
                             f"or raise max_indentations")

    def check_kinematics(self) -> None:
        """Raise InputError for what finite kinematics does not run yet (fem.contact.finite): scans,
        viscoelastic layers and indentors `fem.contact.surfaces.RigidSurface` does not model
        (`check_modelled`)."""
        if self.kinematics not in ("linear", "finite"):
            raise InputError(f'kinematics must be "linear" or "finite", got {self.kinematics!r}')
        if self.kinematics == "linear":
            return
        why = "viscoelastic layers" if self.viscoelastic is not None else None
        for exp in self.experiments:
            if why is None and exp.trace is not None and exp.trace.shape == "scan":
                why = f"experiment '{exp.name}': a scan"
        if why:
            raise InputError(f"kinematics = finite runs by depth or force, swept or in time, so far, not {why}: "
                             f"use kinematics = linear for it")
        for exp in self.experiments:
            try:
                check_modelled(exp.indentor)
            except InputError as exc:
                raise InputError(f"kinematics = finite, experiment '{exp.name}': {exc}") from None

    def check_dim(self, dim: int) -> None:
        """Raise InputError if an experiment cannot run on a model of `dim` (`Experiment.check_dim`)."""
        for exp in self.experiments:
            exp.check_dim(dim)
        if self.afferents is not None and dim != 3:
            raise InputError("[afferents] lie over a pad: they need a 3D model (mesh a preset or a "
                             "reconstruction in 3D); a 2D section has no pad area")


def _check_viscoelastic(source: str, experiments, afferents) -> None:
    """InputError for what viscoelastic layers cannot answer: an experiment without a time course
    (relaxation needs one) or afferents driven by the strain energy density (the correspondence
    principle relaxes stresses, not sigma:eps)."""
    untimed = [e.name for e in experiments if e.trace is None]
    if untimed:
        raise InputError(f"{source}: [viscoelastic] layers relax over time, but experiment '{untimed[0]}' has no "
                         f"time course: give it an [experiment.trace] or leave out viscoelastic")
    if afferents is not None and afferents.input != "stress":
        raise InputError(f'{source}: [afferents] input = "{afferents.input}" with [viscoelastic] layers: only '
                         f'stresses relax (fem.experiments.viscoelastic); use input = "stress"')


def load_scene(path, max_indentations: int | None = None) -> Scene:
    """Read a TOML scene file (`Scene.from_dict`; max_indentations: the bound instead of the
    file's own); a bare name that is no file, such as "ramp_hold", is the shipped scene of that
    name (`fingertip.resources`)."""
    if not Path(path).exists() and (found := shipped_scene(str(path))) is not None:
        path = found
    try:
        with open(path, "rb") as fh:
            d = tomllib.load(fh)
    except (OSError, ValueError) as exc:             # TOMLDecodeError, UnicodeDecodeError are ValueErrors
        raise InputError(f"cannot read scene '{path}': {' '.join(str(exc).split())} (the shipped scenes are "
                         f"{', '.join(scene_names())})") from None
    return Scene.from_dict(d, f"scene '{path}'", max_indentations)
