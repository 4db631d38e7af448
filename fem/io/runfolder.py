"""The run folder of `pipeline.py indent`: its writer (`write_run`) and reader (`IndentRun`).

Per experiment <name>:
- <name>.csv: one row per indentation (step, offset_x_mm, offset_z_mm, depth_mm, force_N,
  force_part<k>_N for multi-part indentors, contact area and width, peak pressure, KKT residuals);
- <name>_surface.csv: per step every contact candidate: x_mm, y_mm, z_mm, deflection_mm,
  pressure_MPa, force_N;
- <name>_receptors.csv: per step every receptor point: site, x_mm, y_mm, z_mm, depth_mm and the
  measures of the scene;
- optionally <name>.pvd with one <name>_<step>.vtu of the full fields per indentation
  (the PNGs beside them are drawn by fem.plots.indent_figures).
run.json (format RUN_FORMAT) records the model, material, receptors and experiments.
"""
from __future__ import annotations

import csv
import hashlib
import json
from concurrent.futures import ThreadPoolExecutor
from dataclasses import asdict
from importlib import metadata
from pathlib import Path

import numpy as np

from fem.core.measures import base_measure
from fem.io.nwb import write_nwb
from fem.io.vtu import fields_mesh, vtu_mesh, write_mesh
from fingertip.errors import InputError
from fingertip.progress import as_progress
from fingertip.staging import write_json
from fingertip.tables import columns_of, write_csv

RUN_FORMAT = 1
"""Version of the run.json layout (raise it when a key changes meaning)."""
RECEPTOR_COLUMNS = ("step", "site", "x_mm", "y_mm", "z_mm", "depth_mm")
"""Columns of `<name>_receptors.csv` that are not measures."""

# --------------------------------------------------------------------------- run.json
def experiment_record(run) -> dict:
    """run.json entry of one experiment (fem.experiments.runner.ExperimentRun): indentor (code, shapes,
    diameter where it has one), placement, sweep axis and offsets (mm), loading, and whether its
    linear results are within their range (`validity`, fem.experiments.runner.linear_validity);
    a viscoelastic time course adds its method and forces (`viscoelastic`,
    fem.experiments.viscoelastic.record)."""
    exp, place, ind = run.experiment, run.placement, run.indentor
    shapes = [{"shape": type(p).__name__, **{k: (None if v == np.inf else v) for k, v in asdict(p).items()}}
              for p in ind.parts]
    diameters = {p.get("diameter_mm") for p in shapes}
    loads = exp.loads
    if exp.force_N is not None:
        loading = {"force_N": loads[0]["force_N"], "equal_force": loads[0]["equal_force"],
                   "max_depth_mm": loads[0]["max_depth_mm"]}
    else:
        loading = {"depth_mm": [d["depth_mm"] for d in loads]}
    if exp.trace is not None:
        loading["trace"] = {**asdict(exp.trace), "times_s": exp.times_s.tolist()}
    offsets = exp.offsets_mm
    axis = None if exp.sweep is None else exp.sweep[0]
    return {"name": exp.name, "indentor": exp.indentor, "shapes": shapes,
            "diameter_mm": diameters.pop() if len(diameters) == 1 else None,
            "orientation": place["orientation"], "position_mm": list(place["position_mm"]),
            "incline_deg": place.get("incline_deg"), "approach": ind.approach.tolist(),
            "length_axis": ind.e1.tolist(), "origin_mm": ind.origin_mm.tolist(),
            "sweep": None if axis is None else {"axis": "xyz"[axis], "offsets_mm": offsets[:, axis].tolist()},
            "loading": loading, "indentations": len(exp.indentations),
            "validity": getattr(run, "validity", None),
            **({"viscoelastic": run.viscoelastic} if getattr(run, "viscoelastic", None) else {}),
            "files": [f"{exp.name}.csv", f"{exp.name}_surface.csv", f"{exp.name}_receptors.csv"]}


KINEMATICS = {"linear": {"name": "linear", "strain": "small strain", "gap": "along the approach, undeformed surface"},
              "finite": {"name": "finite", "strain": "Green-Lagrange, volumetric part from the pressure field",
                         "stress": "Cauchy", "sed": "neo-Hookean stored energy per reference volume",
                         "gap": "normal projection onto the indentor, deformed surface"}}
"""run.json's "kinematics" entry per scene kinematics (docs/indentation.md)."""


def run_record(model_dir, scene_run) -> dict:
    """run.json: what produced a run folder (model, material, receptors, experiments) from a
    model folder and its fem.experiments.runner.SceneRun."""
    model, info, grid, line = scene_run.model, scene_run.info, scene_run.grid, scene_run.line
    folder = Path(model_dir).resolve()
    info_file = folder / "model.json"
    try:
        version = metadata.version("fingertip-fem")
    except metadata.PackageNotFoundError:
        version = None
    mat = model.material
    nus = set(mat.nu.values())
    law = scene_run.scene.viscoelastic
    return {"format": RUN_FORMAT, "package": "fingertip-fem", "version": version,
            "model": {"folder": str(folder), "dim": model.dim, "preset": info.get("preset"),
                      "model_json_sha256": hashlib.sha256(info_file.read_bytes()).hexdigest()
                      if info_file.is_file() else None,
                      "diameter_mm": info.get("params", {}).get("diameter_mm"), "dofs": int(model.ndof)},
            "material": mat.code, "E_MPa": {str(k): v for k, v in sorted(mat.E_MPa.items())},
            "nu": nus.pop() if len(nus) == 1 else {str(k): v for k, v in sorted(mat.nu.items())},
            **({"viscoelastic": law.record()} if law is not None else {}),
            "kinematics": KINEMATICS[scene_run.scene.kinematics],
            "peak_pressure_radius_mm": scene_run.peak_pressure_radius_mm,
            "receptors": {"depths_mm": np.unique(grid.depth_mm).tolist(),
                          "spacing_mm": float(scene_run.scene.receptors.spacing_mm),
                          "line": None if line is None else ["xyz"[line[0]], line[1]],
                          "measures": list(scene_run.measures),
                          "sites": len(grid.sites_mm), "points": len(grid.points_mm),
                          "site_column": "site: id of the surface site (row of sites_mm), the same in every "
                                         "step, position and experiment of this folder"},
            "experiments": [experiment_record(e) for e in scene_run.experiments]}


def afferents_record(population, responses, nwb: bool = False) -> dict | None:
    """run.json entry of a scene's afferents (fem.experiments.spiking): counts per class, the files of
    each traced experiment (with NWB_FILE when nwb) and the loads its 5 kHz inputs were tabulated
    at (null: read from the samples, a scan); None without afferents."""
    if population is None:
        return None
    names, counts = np.unique(population.afferent_class.astype(str), return_counts=True)
    files = AFFERENT_FILES + ((NWB_FILE,) if nwb else ())
    return {"counts": {str(k): int(c) for k, c in zip(names, counts)},
            "experiments": {name: [f"{name}/{f}" for f in files] for name in responses},
            "table_loads": {name: r.table_loads for name, r in responses.items()}}


AFFERENT_FILES = ("afferents.csv", "spikes.csv", "inputs.csv")
"""Files of a traced experiment's afferents, in the folder <experiment name>/ (`write_afferents`)."""
NWB_FILE = "spikes.nwb"
"""The NWB file of a traced experiment's afferents when the scene asks for it (fem.io.nwb)."""

def afferent_tables(resp) -> dict:
    """{"afferents", "spikes", "inputs": {column: values}} of a fem.receptors.afferents.PopulationResponse:
    one row per afferent (site, depth, spike count, mean rate over the course), per spike, and per
    afferent and sample time (static input, surface deflection)."""
    pop = resp.population
    n, k = len(pop), len(resp.times_s)
    site = pop.site_mm
    counts = np.array([len(s) for s in resp.spikes])
    who = np.repeat(np.arange(n), counts)
    rate = resp.rates_hz()
    cls = pop.afferent_class.astype(str)
    afferents = {"afferent_id": np.arange(n), "class": cls, "model_index": pop.model_index,
                 "x_mm": site[:, 0], "y_mm": site[:, 1], "z_mm": site[:, 2], "depth_mm": pop.depth_mm,
                 "spikes": counts, "rate_hz": rate, "peak_input": resp.static.max(axis=1)}
    spikes = {"afferent_id": who, "class": cls[who], "x_mm": site[who, 0], "y_mm": site[who, 1],
              "z_mm": site[who, 2], "depth_mm": pop.depth_mm[who],
              "time_s": np.concatenate(resp.spikes) if n else np.zeros(0)}
    inputs = {"afferent_id": np.repeat(np.arange(n), k), "time_s": np.tile(resp.times_s, n),
              "input": resp.static.ravel(), "deflection_mm": resp.deflection_mm.ravel()}
    return {"afferents": afferents, "spikes": spikes, "inputs": inputs}


def write_afferents(folder, resp) -> dict:
    """AFFERENT_FILES of one traced experiment into `folder` (created); returns its tables."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    tables = afferent_tables(resp)
    for name, file in zip(("afferents", "spikes", "inputs"), AFFERENT_FILES):
        write_csv(folder / file, tables[name])
    return tables


# --------------------------------------------------------------------------- writer
def writes_pvd(output, indentations: int) -> bool:
    """Whether an experiment of `indentations` indentations writes a PVD series under a scene's
    `output` (fem.experiments.scene.Output): only when asked (pvd = true, --pvd), since full fields
    need the factorised model and everything else is answered by the stored response model."""
    return bool(output.pvd) and indentations > 0


def write_run(folder, model_dir, scene_run, afferents=(None, {}), progress=None) -> dict[str, dict]:
    """Every experiment's CSVs (and PVD series), its afferents' (`write_afferents`, from
    afferents = (population, {experiment name: response}) of fem.receptors.afferents.scene_responses) and
    run.json into `folder` (an existing, usually staged, folder). Returns {experiment name: its
    tables (`run_tables`, with "afferents": `afferent_tables` for a traced experiment)} for the plots.
    progress: a fingertip.progress object (None: silent); writing shows a bar per experiment."""
    folder = Path(folder)
    out = scene_run.scene.output
    population, responses = afferents
    progress = as_progress(progress)
    written = {}
    for run in progress.bar(scene_run.experiments, desc="writing the run folder", unit="experiment"):
        tables = written[run.name] = run_tables(run, scene_run)
        write_csv(folder / f"{run.name}.csv", tables["steps"])
        write_csv(folder / f"{run.name}_surface.csv", tables["surface"])
        write_csv(folder / f"{run.name}_receptors.csv", tables["receptors"])
        if run.name in responses:
            tables["afferents"] = write_afferents(folder / run.name, responses[run.name])
            if scene_run.scene.afferents.nwb:
                write_nwb(folder / run.name / NWB_FILE, run.name, responses[run.name],
                          tables["steps"]["depth_mm"], tables["steps"]["force_N"])
        if writes_pvd(out, len(run.steps)):
            _write_pvd(folder, run, scene_run, progress)
    record = run_record(model_dir, scene_run)
    if population is not None:
        record["afferents"] = afferents_record(population, responses, scene_run.scene.afferents.nwb)
    write_json(folder / "run.json", record)
    return written


def _width_mm(res, ind, x3, dim) -> float:
    """Contact width across the indentor (mm): the span of the nodes carrying force (2D: area)."""
    if dim == 2:
        return res.contact_area_mm2
    v = (x3[res.active] @ ind.e2) if res.active.any() else np.zeros(1)
    return float(v.max() - v.min())


def pad3(x) -> np.ndarray:
    """(n, 3) points from (n, dim) ones (z = 0 in 2D)."""
    out = np.zeros((len(x), 3))
    out[:, :x.shape[1]] = x
    return out


def stored_energy_Nmm(result) -> float:
    """Strain energy stored in the whole linear elastic model by an indentation [N mm; N mm per mm
    in 2D]: u^T K u / 2 = f . w / 2 with f the nodal contact forces and w the deflections along the
    approach (no other load does work; the held regions do not move). Frictionless contact stores
    the indentor's work: it equals the integral of force over depth (tests/fem/contact). A finite
    kinematics result carries its own (the neo-Hookean energy, fem.contact.finite)."""
    if result.stored_energy_Nmm is not None:
        return result.stored_energy_Nmm
    return 0.5 * float(np.nansum(result.force_N * result.deflection_mm))


def run_tables(run, scene_run) -> dict:
    """{"steps", "surface", "receptors": {column: values}, "values": {measure: (k, n)}} of one experiment."""
    sn, sampler, measures, dim = scene_run.surface, scene_run.sampler, scene_run.measures, scene_run.model.dim
    ind, steps = run.indentor, run.steps
    x3 = pad3(sn.x)
    times = run.experiment.times_s
    rows = [{"step": i, **({} if times is None else {"time_s": float(times[i])}), "offset_x_mm": off[0], "offset_z_mm": off[2],
             "depth_mm": float(r.depth_mm.max()), "force_N": r.total_force_N,
             **{f"force_part{k}_N": f for k, f in enumerate(r.part_force_N) if len(r.depth_mm) > 1},
             "energy_Nmm": stored_energy_Nmm(r) if run.viscoelastic is None else float("nan"),
             "contact_area_mm2": r.contact_area_mm2, "contact_width_mm": _width_mm(r, ind, x3, dim),
             "max_pressure_MPa": r.max_pressure_MPa,
             "peak_pressure_MPa": scene_run.peak_pressure_MPa(r.force_N),
             "penetration_mm": r.kkt["penetration_mm"],
             "tensile_N": r.kkt["tensile_N"], "complementarity_Nmm": r.kkt["complementarity_Nmm"],
             "kkt_ok": r.kkt["ok"]} for i, (off, r) in enumerate(steps)]
    k, m = len(steps), len(x3)
    surface = {"step": np.repeat(np.arange(k), m), "x_mm": np.tile(x3[:, 0], k), "y_mm": np.tile(x3[:, 1], k),
               "z_mm": np.tile(x3[:, 2], k),
               "deflection_mm": np.concatenate([r.deflection_mm for _, r in steps]),
               "pressure_MPa": np.concatenate([r.pressure_MPa for _, r in steps]),
               "force_N": np.concatenate([r.force_N for _, r in steps])}
    grid = sampler.grid
    pts, n = pad3(grid.points_mm), len(grid.points_mm)
    per_step = [sampler.measures(r.observed, measures) for _, r in steps]
    values = {name: np.stack([np.asarray(v[name], float) for v in per_step]) for name in measures}
    receptors = {"step": np.repeat(np.arange(k), n), "site": np.tile(np.asarray(grid.site), k),
                 "x_mm": np.tile(pts[:, 0], k), "y_mm": np.tile(pts[:, 1], k), "z_mm": np.tile(pts[:, 2], k),
                 "depth_mm": np.tile(np.asarray(grid.depth_mm, float), k),
                 **{name: values[name].ravel() for name in measures}}
    return {"steps": columns_of(rows), "surface": surface, "receptors": receptors, "values": values}


def pvd_times(run) -> tuple[list[float], str]:
    """(timestep value per indentation, its meaning) of an experiment's PVD series: the offset
    along the sweep axis [mm] for a sweep, else the depth reached [mm] (prescribed, or found under
    force control); the step index when those do not increase strictly (a sweep at several loads,
    repeated depths)."""
    exp = run.experiment
    if exp.sweep is not None:
        axis = exp.sweep[0]
        values, meaning = [float(off[axis]) for off, _ in run.steps], f"{'xyz'[axis]} offset of the sweep in mm"
    else:
        values, meaning = [float(r.depth_mm.max()) for _, r in run.steps], "depth reached in mm"
    if any(b <= a for a, b in zip(values, values[1:])):
        return [float(i) for i in range(len(run.steps))], "step index"
    return values, meaning


def _write_pvd(folder, run, scene_run, progress) -> None:
    """<name>_<step>.vtu with the full fields of every indentation and the <name>.pvd series, its
    timestep values as `pvd_times` says. A viscoelastic step's fields are its elastic solution's:
    its displacements and strains, not its relaxed stresses (a course stepped in time: its own
    displacements); a finite kinematics step's are its deformed state's (`run.finite_fields`)."""
    if run.finite_fields is not None:              # finite kinematics: the deformed state's own
        meshes = [fields_mesh(scene_run.model, u, fields, deformed=True) for u, fields in run.finite_fields]
    else:
        if run.stepped is not None:                 # a course stepped in time keeps its fields
            U = run.stepped.displacement_mm
        else:
            comp = scene_run.contact.compliance(run.indentor.approach)
            forces = [r.force_N if r.elastic_force_N is None else r.elastic_force_N for _, r in run.steps]
            U = comp.displacement(np.stack(forces, axis=1))                      # one solve, k loads
        meshes = [vtu_mesh(scene_run.model.solution(U[:, i])) for i in range(len(run.steps))]
    names = [f"{run.name}_{i:03d}.vtu" for i in range(len(run.steps))]
    with ThreadPoolExecutor(max_workers=2) as pool:     # files compress in parallel (zlib frees the GIL)
        writes = [pool.submit(write_mesh, folder / name, mesh) for name, mesh in zip(names, meshes)]
        for w in progress.bar(writes, desc=f"{run.name}: VTU files", unit="file"):
            w.result()
    times, meaning = pvd_times(run)
    entries = "\n".join(f'    <DataSet timestep="{t:.9g}" file="{n}"/>' for t, n in zip(times, names))
    (folder / f"{run.name}.pvd").write_text('<?xml version="1.0"?>\n<VTKFile type="Collection" version="0.1">\n'
                                            f"  <!-- timestep: {meaning} -->\n"
                                            f"  <Collection>\n{entries}\n  </Collection>\n</VTKFile>\n")


# --------------------------------------------------------------------------- reader
class IndentRun:
    """A run folder of `pipeline.py indent`: per experiment `<name>.csv` (one row per
    indentation, `offset_x_mm`, `offset_z_mm`, ...), `<name>_receptors.csv` (per indentation
    every receptor point: site, x_mm, y_mm, z_mm, depth_mm and the measures the run computed) and
    `run.json` (model, indentor, sweep axis, receptors; see docs/file-formats.md).

    Receptor sites are identified by the `site` column (the same id at every depth, step and
    position). `diameter_mm` (2D cylinders) and each stimulus's sweep axis come from run.json."""
    def __init__(self, folder, diameter_mm: float | None = None):
        self.folder = Path(folder)
        if self.folder.exists() and not self.folder.is_dir():
            raise InputError(f"'{folder}' is a file, not an indentation results folder: give the folder "
                             f"`pipeline.py indent` wrote")
        if not self.folder.is_dir():
            raise InputError(f"no indentation results folder '{folder}': run `pipeline.py indent` first")
        self.stimuli = sorted(p.name[:-len("_receptors.csv")] for p in self.folder.glob("*_receptors.csv")
                              if (self.folder / (p.name[:-len("_receptors.csv")] + ".csv")).is_file())
        if not self.stimuli:
            raise InputError(f"'{folder}' holds no <name>.csv + <name>_receptors.csv pairs from "
                             f"`pipeline.py indent`")
        record = self.folder / "run.json"
        if not record.is_file():
            raise InputError(f"'{folder}' has no run.json: it was written by an older version; re-run "
                             f"`pipeline.py indent`")
        try:
            self.run = json.loads(record.read_text())
            self._experiments = {e["name"]: e for e in self.run["experiments"]}
        except (ValueError, KeyError, TypeError):
            raise InputError(f"'{record}' is not a run.json written by `pipeline.py indent`") from None
        if diameter_mm is None:
            diameter_mm = self.run.get("model", {}).get("diameter_mm")
        self.diameter_mm = None if diameter_mm is None else float(diameter_mm)
        self._cache = {}

    def sweep_axis(self, stimulus) -> str | None:
        """'x' or 'z' for a sweep, None for fixed positions or a stimulus run.json does not list
        (a folder keeps the files of earlier runs; run.json describes the last one)."""
        sweep = self._experiments.get(stimulus, {}).get("sweep")
        return None if sweep is None else sweep["axis"]

    def __repr__(self):
        return f"IndentRun('{self.folder}', stimuli={self.stimuli}, diameter_mm={self.diameter_mm})"

    def _load(self, stimulus):
        if stimulus in self._cache:
            return self._cache[stimulus]
        if stimulus not in self.stimuli:
            raise InputError(f"stimulus '{stimulus}' is not in '{self.folder}': it holds {self.stimuli} "
                             f"(the neural CSV's stimulus must name an indentation experiment)")
        steps = _read_csv(self.folder / f"{stimulus}.csv")
        offx = np.array([float(r["offset_x_mm"]) for r in steps])
        offz = np.array([float(r["offset_z_mm"]) for r in steps])
        if stimulus in self._experiments:
            along_z = self.sweep_axis(stimulus) == "z"
        else:                       # files of an earlier run: the axis with the larger offset range
            along_z = np.ptp(offz) > np.ptp(offx)
        position = offz if along_z else offx
        path = self.folder / f"{stimulus}_receptors.csv"
        with open(path) as fh:
            header = fh.readline().strip().split(",")
        if "site" not in header:
            raise InputError(f"'{path}' has no site column: it was written by an older version; re-run "
                             f"`pipeline.py indent`")
        table = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)
        step = table[:, 0].astype(int)
        n_steps = len(steps)
        per = np.bincount(step, minlength=n_steps)
        if per.min() != per.max() or per[0] == 0:
            raise InputError(f"'{stimulus}_receptors.csv' does not hold the same receptor points for every step")
        n = per[0]
        keys = (table[:, header.index("depth_mm")], table[:, header.index("site")], step)
        table = table[np.lexsort(keys)]     # by step (then site and depth: row order does not matter)
        cols = {h: table[:, k].reshape(n_steps, n) for k, h in enumerate(header)}
        depth = cols["depth_mm"][0]
        depths = np.unique(depth)
        site = cols["site"][0].astype(int)
        if np.any(cols["site"] != site) or np.any(cols["depth_mm"] != depth):
            raise InputError(f"'{stimulus}_receptors.csv': the receptor sites differ between steps")
        sites = set(site[depth == depths[0]])
        if any(set(site[depth == d]) != sites or (depth == d).sum() != len(sites) for d in depths):
            raise InputError(f"'{stimulus}_receptors.csv': not every receptor site appears once at every depth")
        data = {"position": position, "along_z": along_z, "depth": depth, "site": site, "depths": depths,
                "x": cols["x_mm"][0], "y": cols["y_mm"][0], "z": cols["z_mm"][0],
                "values": {h: cols[h] for h in header if h not in RECEPTOR_COLUMNS}, "steps": steps}
        self._cache[stimulus] = data
        return data

    def steps(self, stimulus) -> list[dict]:
        """Rows of `<stimulus>.csv`, one per indentation ({column: text})."""
        return self._load(stimulus)["steps"]

    def positions(self, stimulus) -> np.ndarray:
        """(k,) stimulus offsets of the sweep (mm)."""
        return self._load(stimulus)["position"]

    def depths(self, stimulus) -> np.ndarray:
        return self._load(stimulus)["depths"]

    def measures(self, stimulus) -> list[str]:
        return list(self._load(stimulus)["values"])

    def values(self, stimulus, candidate) -> np.ndarray:
        """(k_steps, n_points) values of a candidate measure (a fem.core.measures name or abs:<name>)
        at every receptor point."""
        name = base_measure(candidate)
        vals = self._load(stimulus)["values"]
        if name not in vals:
            raise InputError(f"measure '{name}' was not computed in '{self.folder / stimulus}_receptors.csv' "
                             f"(it has {list(vals)}): re-run `pipeline.py indent` with a scene whose "
                             f"[receptors] measures list it (examples/analysis_gratings.toml lists all candidates)")
        v = vals[name]
        return np.abs(v) if candidate.startswith("abs:") else v

    def site_index(self, stimulus, receptor_x_mm: float = 0.0, receptor_z_mm: float | None = None) -> int:
        """Site id (the `site` column) of the receptor site nearest the lateral position (x, and z
        in 3D; default the middle z), judged at the shallowest depth."""
        d = self._load(stimulus)
        top = d["depth"] == d["depths"][0]
        z = d["z"][top]
        rz = 0.5 * (z.min() + z.max()) if receptor_z_mm is None else receptor_z_mm
        return int(d["site"][top][np.argmin((d["x"][top] - receptor_x_mm) ** 2 + (z - rz) ** 2)])

    def profile(self, stimulus, candidate, depth_mm, receptor_x_mm=0.0, site=None, align=True):
        """Spatial response profile: (positions (k,), values (k,)) of one receptor (the site
        nearest receptor_x_mm, at the listed depth nearest depth_mm) as the stimulus steps.

        align (sweeps along x; a single indentation is never moved): the site's profile is
        translated by receptor_x_mm - site x, i.e.
        it stands for a receptor exactly at receptor_x_mm (the sites of an `indent` grid are the
        surface nodes nearest the centres of cells of its spacing, 0.015 mm off x = 0 on the 2D
        cylinders; two runs of different diameters then describe the same receptor)."""
        d = self._load(stimulus)
        depth = d["depths"][np.argmin(np.abs(d["depths"] - depth_mm))]
        s = self.site_index(stimulus, receptor_x_mm) if site is None else site
        j = np.flatnonzero((d["depth"] == depth) & (d["site"] == s))[0]
        shift = 0.0
        if align and not d["along_z"] and len(d["position"]) > 1:
            shift = receptor_x_mm - d["x"][np.flatnonzero((d["depth"] == d["depths"][0]) & (d["site"] == s))[0]]
        return d["position"] + shift, self.values(stimulus, candidate)[:, j]

    def population(self, stimulus, candidate, depth_mm, position_mm):
        """Population response: (receptor x (n,), values (n,)) of all receptors at one depth for the
        indentation nearest position_mm, ordered by x."""
        d = self._load(stimulus)
        depth = d["depths"][np.argmin(np.abs(d["depths"] - depth_mm))]
        i = int(np.argmin(np.abs(d["position"] - position_mm)))
        sel = np.flatnonzero(d["depth"] == depth)
        sel = sel[np.argsort(d["x"][sel])]
        return d["x"][sel], self.values(stimulus, candidate)[i, sel]


def _read_csv(path) -> list[dict]:
    with open(path) as fh:
        return list(csv.DictReader(fh))
