"""One stimulus at a time from a model folder's stored response model: what the live explorer
(`pipeline.py explore`) shows while a user moves an indentor over the pad, asked the same way from
a notebook.

    live = LiveModel("out/monkey")          # finds (or builds and stores, once) the response model
    a = live.answer({"indentor": "C5", "orientation": "perpendicular", "position_mm": [0, 3.75],
                     "depth_mm": 1.0})
    a.force_N, a.contact_area_mm2, a.peak_pressure_MPa     # one indentation's numbers
    a.surface["pressure_MPa"], a.receptors["sed_MPa"]      # per contact candidate, per receptor point
    Path("here.toml").write_text(live.scene_toml(a.experiment))   # `pipeline.py indent` reproduces it
    f = live.fire(a.experiment, "SA1")      # 3D: SA1 afferents under a ramp-and-hold to that stimulus
    f.afferents["rate_hz"]                  # per afferent, as <experiment>/afferents.csv of `indent`

An answer is `fem.experiments.runner.run_experiments` of a scene with that one experiment, answered by
the folder's `fem.experiments.response.ResponseStore`, read into the columns of the run folder's
tables (`fem.io.runfolder.run_tables`): the numbers `pipeline.py indent` writes for the saved scene,
to round-off. On the monkey 1.0 mm model an answer takes about 15 ms.

Afferents (`fire`) need the stress at their own sites, which the stored response model does not
hold: each firing is `fem.experiments.runner.run_scene` of the scene `scene_toml` saves with the
afferent class (the stimulus reached by AFFERENT_TRACE, [afferents] of that class at the published
density over the pad), which factorises the model as `pipeline.py indent` does.
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from fem.contact.facets import fe_facets
from fem.experiments.runner import (
    prepare_responses,
    run_experiments,
    run_scene,
    validity_warning,
)
from fem.experiments.scene import Receptors, Scene
from fem.io.modelfolder import CONTACT_REGION, read_model
from fem.io.runfolder import afferent_tables, run_tables
from fingertip.errors import InputError

AFFERENT_TRACE = {"shape": "ramp_hold", "ramp_s": 0.1, "hold_s": 0.5, "release_s": 0.1, "samples": 100}
"""The time course the explorer's afferents feel: a ramp to the stimulus's depth (or force) in
0.1 s, held 0.5 s, released in 0.1 s ([experiment.trace], fem.experiments.traces)."""


@dataclass
class Answer:
    """One indentation of `experiment` (its [[experiment]] table): the run's step row ({column:
    value}, the step table's columns), its surface table (per contact candidate: x_mm, y_mm, z_mm,
    deflection_mm, pressure_MPa, force_N, (m,) each), its receptor table (per receptor point:
    x_mm, y_mm, z_mm, depth_mm and one (n,) column per measure), the approach (3,), the warnings
    of the run (placement, linear range) and the seconds it took."""
    experiment: dict
    step: dict
    surface: dict
    receptors: dict
    approach: np.ndarray
    warnings: list
    seconds: float

    @property
    def force_N(self) -> float:
        """Total force along the approach [N; N per mm of length in 2D]."""
        return float(self.step["force_N"])

    @property
    def depth_mm(self) -> float:
        """Travel beyond first touch [mm] (solved for under force control)."""
        return float(self.step["depth_mm"])

    @property
    def contact_area_mm2(self) -> float:
        """Contact area [mm^2; the contact width in mm in 2D]."""
        return float(self.step["contact_area_mm2"])

    @property
    def max_pressure_MPa(self) -> float:
        """Largest contact pressure at a node [MPa]."""
        return float(self.step["max_pressure_MPa"])

    @property
    def peak_pressure_MPa(self) -> float:
        """Largest contact pressure averaged over fem.contact.facets.PEAK_PRESSURE_RADIUS_MM [MPa]."""
        return float(self.step["peak_pressure_MPa"])


@dataclass
class Firing:
    """The afferents of one class under AFFERENT_TRACE to one stimulus: afferents, the run's
    afferent table (one row per afferent: class, x_mm, y_mm, z_mm of its site, depth_mm, spikes,
    rate_hz (mean over the course), ..., as <experiment>/afferents.csv of `pipeline.py indent`), the
    fem.receptors.afferents.PopulationResponse and the seconds it took."""
    afferent_class: str
    afferents: dict
    response: object
    seconds: float

    @property
    def firing(self) -> np.ndarray:
        """(n,) bool: the afferents that fire at least once."""
        return np.asarray(self.afferents["spikes"]) > 0


class LiveModel:
    """A model folder held in memory with its stored response model, answering one experiment at a
    time. material, nu: as a scene's (default: the model's); receptors: a scene's [receptors] table
    (default depths and spacing). The response model for the model's support approach is found or
    built (shown on `progress`) when the LiveModel is made; an experiment with another approach
    (incline_deg, approach) builds its own on first use."""

    def __init__(self, model_dir, material=None, nu=None, receptors: dict | None = None, progress=None):
        self.model_dir = Path(model_dir)
        self.base = {key: value for key, value in (("material", material), ("nu", nu)) if value is not None}
        self.base["receptors"] = dict(receptors or {})
        self.base["output"] = {"pvd": False}        # answered by the stored model, not factorised
        rc = Receptors.from_dict(self.base["receptors"])
        self.model, self.info = read_model(model_dir, material, nu)
        self.prepared = prepare_responses(model_dir, material, nu, receptors=rc, progress=progress)
        self.store = self.prepared.store
        self.depths_mm = tuple(float(d) for d in rc.depths_mm)
        self.measures = tuple(rc.measures)
        self.surface_nodes = self.model.surface_nodes(CONTACT_REGION[self.model.dim])
        self.facets = fe_facets(self.model, CONTACT_REGION[self.model.dim], self.surface_nodes)[0]

    @property
    def dim(self) -> int:
        """2 (plane strain) or 3."""
        return self.model.dim

    @property
    def pad_mm(self) -> np.ndarray:
        """(m, dim) undeformed contact candidates, the rows of every answer's surface table."""
        return self.surface_nodes.x

    def scene_dict(self, experiment: dict, afferent_class: str | None = None) -> dict:
        """The scene of one experiment table as a dict; with afferent_class, the stimulus is reached
        by AFFERENT_TRACE and [afferents] has that class."""
        if afferent_class is None:
            return {**self.base, "experiment": [dict(experiment)]}
        return {**self.base, "afferents": {"classes": [afferent_class]},
                "experiment": [{**experiment, "trace": dict(AFFERENT_TRACE)}]}

    def scene(self, experiment: dict, afferent_class: str | None = None) -> Scene:
        """`scene_dict` as a Scene (InputError for a bad table or class, or afferents on a 2D model)."""
        scene = Scene.from_dict(self.scene_dict(experiment, afferent_class), source="the explorer's scene")
        scene.check_dim(self.dim)
        return scene

    def answer(self, experiment: dict) -> Answer:
        """The indentation of one [[experiment]] table with a single depth_mm or a force_N."""
        scene = self.scene(experiment)
        exp = scene.experiments[0]
        if len(exp.indentations) != 1 or exp.trace is not None:
            raise InputError("the explorer answers one indentation: give one depth_mm or a force_N, no sweep or trace")
        t0 = time.perf_counter()
        run_all = run_experiments(self.model, self.info, scene, store=self.store)
        run = run_all.experiments[0]
        tables = run_tables(run, run_all)
        warnings = list(run_all.warnings) + [w for w in [validity_warning(run)] if w]
        step = {key: values[0] for key, values in tables["steps"].items()}
        receptors = {key: np.asarray(v) for key, v in tables["receptors"].items() if key != "step"}
        surface = {key: np.asarray(v) for key, v in tables["surface"].items() if key != "step"}
        return Answer(dict(experiment), step, surface, receptors, np.asarray(run.indentor.approach, float),
                      warnings, time.perf_counter() - t0)

    def fire(self, experiment: dict, afferent_class: str, progress=None) -> Firing:
        """The afferents of afferent_class under AFFERENT_TRACE to the stimulus of one experiment
        table (3D models): `pipeline.py indent` of the scene `scene_toml(experiment, afferent_class)`,
        in process (it factorises the model; progress: a `fingertip.progress` object)."""
        scene = self.scene(experiment, afferent_class)
        t0 = time.perf_counter()
        run = run_scene(self.model_dir, scene, progress=progress)
        response = run.afferents[1][scene.experiments[0].name]
        return Firing(afferent_class, afferent_tables(response)["afferents"], response, time.perf_counter() - t0)

    def scene_toml(self, experiment: dict, comment: str = "", afferent_class: str | None = None) -> str:
        """The scene of one experiment (with afferent_class: its afferents, `scene_dict`) as TOML
        text that `pipeline.py indent MODEL --scene FILE` runs (checked first)."""
        self.scene(experiment, afferent_class)
        d = self.scene_dict(experiment, afferent_class)
        lines = [f"# {line}" for line in comment.splitlines()] + [
            f"# {self.model_dir.name}: pipeline.py indent {self.model_dir} --scene <this file>"]
        lines += [f"{key} = {toml_value(d[key])}" for key in ("material", "nu") if key in d]
        for table in ("receptors", "output", "afferents"):
            if d.get(table):
                lines += ["", f"[{table}]"] + [f"{k} = {toml_value(v)}" for k, v in d[table].items()]
        exp = d["experiment"][0]
        lines += ["", "[[experiment]]"] + [f"{k} = {toml_value(v)}" for k, v in exp.items() if k != "trace"]
        if "trace" in exp:
            lines += ["", "[experiment.trace]"] + [f"{k} = {toml_value(v)}" for k, v in exp["trace"].items()]
        return "\n".join(lines) + "\n"


def toml_value(value) -> str:
    """A TOML value of a scene: a string, a boolean, a finite number or a list of them."""
    if isinstance(value, str):
        return '"' + value.replace("\\", "\\\\").replace('"', '\\"') + '"'
    if isinstance(value, (bool, np.bool_)):
        return "true" if value else "false"
    if isinstance(value, (int, np.integer)):
        return str(int(value))
    if isinstance(value, (float, np.floating)):
        if not math.isfinite(value):
            raise InputError(f"a scene takes finite numbers, got {value}")
        return repr(float(value))
    if isinstance(value, (list, tuple, np.ndarray)):
        return "[" + ", ".join(toml_value(v) for v in value) + "]"
    raise TypeError(f"no TOML value for {type(value).__name__}")
