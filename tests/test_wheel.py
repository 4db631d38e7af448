"""The package as a wheel, installed outside the repository: it installs fem, reconstruct,
fingertip and pipeline and nothing else, carries the shipped files, and its console script runs
the main job on the bundled images and the ramp-and-hold scene on a preset.

The fresh virtual environment gets the wheel alone; its dependencies come from this test run's
environment through a path entry (installing numpy, scipy, VTK ... afresh would take minutes) and
pypardiso is pointed at this environment's MKL (`PYPARDISO_MKL_RT`, which it reads), and no entry
points back into the repository."""
from __future__ import annotations

import glob
import os
import site
import subprocess
import sys
import zipfile

import pytest

from tests.helpers import ROOT


@pytest.mark.slow
def test_wheel_installed_outside_the_repository_runs_the_main_job_and_a_shipped_scene(tmp_path):
    dist = tmp_path / "dist"
    subprocess.run([sys.executable, "-m", "pip", "wheel", "-q", "--no-deps", str(ROOT),
                    "-w", str(dist)], check=True, capture_output=True, cwd=tmp_path)
    wheel = next(dist.glob("fingertip_fem-*.whl"))
    names = zipfile.ZipFile(wheel).namelist()
    assert {n.split("/")[0] for n in names if not n.startswith("fingertip_fem-")} == {
        "fem", "reconstruct", "fingertip", "pipeline.py"}
    assert "fingertip/bundled/sample_images/turntable.toml" in names
    assert "fingertip/bundled/scenes/ramp_hold.toml" in names
    assert "fingertip/bundled/data/touchsim_afferents.json" in names

    venv = tmp_path / "venv"
    subprocess.run([sys.executable, "-m", "venv", str(venv)], check=True)
    py = venv / "bin" / "python"
    subprocess.run([py, "-m", "pip", "install", "-q", "--no-deps", "--no-index", str(wheel)], check=True,
                   capture_output=True)
    purelib = subprocess.run([py, "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"],
                             check=True, capture_output=True, text=True).stdout.strip()
    deps = [p for p in site.getsitepackages() if "site-packages" in p]
    with open(os.path.join(purelib, "dependencies.pth"), "w") as fh:   # the dependencies, not this checkout
        fh.write("\n".join(deps) + "\n")
    work = tmp_path / "work"
    work.mkdir()
    env = {**os.environ, "PYTHONPATH": ""}            # the user's mesh cache: the quick monkey is usually there
    mkl = sorted(glob.glob(f"{sys.prefix}/lib*/**/libmkl_rt.so*", recursive=True))
    if mkl:                                         # else SciPy stands in for PARDISO (slower, same answers)
        env["PYPARDISO_MKL_RT"] = mkl[0]
    where = subprocess.run([py, "-c", "import fem, fingertip; print(fem.__file__, fingertip.__file__)"],
                           cwd=work, env=env, check=True, capture_output=True, text=True).stdout
    assert str(ROOT) not in where and str(venv) in where
    fingertip = venv / "bin" / "fingertip"

    def run(*argv):
        done = subprocess.run([fingertip, *map(str, argv)], cwd=work, env=env, capture_output=True, text=True,
                              timeout=600)
        assert done.returncode == 0, done.stderr
        return done.stdout

    assert "written to" in run("reconstruct", "--out", "o", "--quiet") or (work / "o" / "sections.json").is_file()
    assert (work / "o" / "sections.json").is_file() and (work / "o" / "report.png").is_file()
    run("mesh", "--preset", "monkey", "--size", "1.5", "--out", "m", "--quiet")
    run("indent", "m", "--scene", "ramp_hold", "--out", "spikes", "--quiet")
    assert (work / "spikes" / "ramp_hold" / "spikes.csv").is_file()
