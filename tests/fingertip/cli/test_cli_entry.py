"""The `fingertip` console script (pyproject.toml [project.scripts]) runs the same command line as
`python pipeline.py`."""
import shutil
import subprocess

import pytest

import pipeline
from tests.helpers import ROOT

FINGERTIP = shutil.which("fingertip")
pytestmark = pytest.mark.skipif(FINGERTIP is None, reason="console script not installed (pip install -e .)")


def test_help_exits_0():
    done = subprocess.run([FINGERTIP, "--help"], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    assert "reconstruct" in done.stdout


def test_reconstruct_matches_pipeline_main(tmp_path, monkeypatch):
    """Same sections.json from the console script as from pipeline.main (same images argument)."""
    script, library = tmp_path / "script", tmp_path / "library"
    done = subprocess.run([FINGERTIP, "reconstruct", "sample_images", "--out", str(script), "--quiet"],
                          cwd=ROOT, capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr
    monkeypatch.chdir(ROOT)
    assert pipeline.main(["reconstruct", "sample_images", "--out", str(library), "--quiet"]) == 0
    assert (script / "sections.json").read_bytes() == (library / "sections.json").read_bytes()
