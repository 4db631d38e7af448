"""The library as a notebook uses it: imported in a fresh interpreter, a 2D model built, indented
and its results read, with no global state changed (matplotlib backend, environment)."""
import json
import subprocess
import sys

from tests.helpers import ROOT

SCRIPT = r"""
import json, os, sys
import matplotlib
env0, rc_backend0 = dict(os.environ), dict.__getitem__(matplotlib.rcParams, "backend")   # unresolved

from fem.geometry.mesh2d import Sizing2D, preset_domain, run_mesh2d
from fem.io.modelfolder import read_model
from fem.experiments.scene import Scene
from fem.experiments.runner import run_experiments
from fem.io.runfolder import IndentRun, write_run
from fem import plots

folder = sys.argv[1]
run_mesh2d(folder + "/cyl8", preset_domain("cylinder8", bone=True), Sizing2D(size_mm=0.25), progress=False)
model, info = read_model(folder + "/cyl8")
scene = Scene.from_dict({"experiment": [{"name": "c5", "indentor": "C5", "depth_mm": "0.5:1:0.5"}],
                         "receptors": {"depths_mm": [0.75], "spacing_mm": 1.0}})
run = run_experiments(model, info, scene)
os.makedirs(folder + "/run")
tables = write_run(folder + "/run", folder + "/cyl8", run)
figures = plots.indent_figures(run.experiments[0], run, tables["c5"])
read = IndentRun(folder + "/run")
print(json.dumps({
    "forces_N": [r.total_force_N for _, r in run.experiments[0].steps],
    "kkt_ok": [bool(r.kkt["ok"]) for _, r in run.experiments[0].steps],
    "stimuli": read.stimuli, "sed_shape": list(read.values("c5", "sed_MPa").shape),
    "figures": sorted(figures),
    "pyplot_loaded": "matplotlib.pyplot" in sys.modules, "env_same": dict(os.environ) == env0,
    "rc_backend_same": dict.__getitem__(matplotlib.rcParams, "backend") == rc_backend0,
    "backend": matplotlib.get_backend()}))
"""


def test_fresh_interpreter_builds_indents_reads_without_global_state(tmp_path):
    out = subprocess.run([sys.executable, "-c", SCRIPT, str(tmp_path)], cwd=ROOT, capture_output=True,
                         text=True, timeout=300, check=True)
    got = json.loads(out.stdout.strip().splitlines()[-1])
    untouched = subprocess.run([sys.executable, "-c", "import matplotlib; print(matplotlib.get_backend())"],
                               capture_output=True, text=True, check=True).stdout.strip()
    assert got["env_same"] and got["rc_backend_same"] and got["backend"] == untouched
    assert not got["pyplot_loaded"]          # figures are drawn on Figure objects, not through pyplot
    assert got["kkt_ok"] == [True, True]
    assert 0 < got["forces_N"][0] < got["forces_N"][1]          # deeper: more force (N per mm)
    assert got["stimuli"] == ["c5"] and got["sed_shape"][0] == 2
    assert got["figures"] == ["c5_force.png", "c5_profile.png", "c5_receptors.png"]
