"""The live explorer: its answers are the command line's (a saved scene run by `indent` gives the same
force and receptor measures to 1e-9, and factorised within the stored model's budget), bad input is refused before any work, and
the web app driven in a real headless browser shows the force of the depth typed into it and the
spikes of the afferents `indent` fires for the scene it saves with them."""
from __future__ import annotations

import os
import shutil
import socket
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from fem.experiments.live import LiveModel, toml_value
from fem.experiments.response import STORED_RTOL, ResponseStore
from fem.experiments.runner import run_scene
from fem.experiments.scene import load_scene
from fem.io.runfolder import run_tables
from fingertip.errors import InputError
from tests.fingertip.cli.test_bad_input import assert_refused
from tests.helpers import CHROMEDRIVER, CHROMIUM, ROOT, cli, headless_chromium, snapshot


def indent_tables(model_dir, scene_file, factorise: bool):
    """Force (N) and receptor table of the one experiment of a saved scene, run as `indent` runs it:
    as saved (answered by the model folder's stored response model) or with a PVD (factorised)."""
    scene = load_scene(scene_file)
    if factorise:
        scene = type(scene)(**{**scene.__dict__, "output": type(scene.output)(pvd=True, plots=False)})
    run = run_scene(model_dir, scene, store=None if factorise else ResponseStore(model_dir))
    assert (run.responses == []) == factorise
    tables = run_tables(run.experiments[0], run)
    return float(tables["steps"]["force_N"][0]), tables["receptors"]


def test_answers_equal_the_factorised_run_of_the_saved_scene(cyl8, tmp_path):
    live = LiveModel(cyl8)
    for experiment in ({"indentor": "C5", "position_mm": [0.3, 0.0], "depth_mm": [0.6]},
                       {"indentor": "bar:1.5", "position_mm": [-0.5, 0.0], "force_N": 0.002}):
        a = live.answer(experiment)
        saved = tmp_path / "scene.toml"
        saved.write_text(live.scene_toml(a.experiment, comment="a test"))
        for factorise, rtol in ((False, 1e-9), (True, STORED_RTOL)):
            force, receptors = indent_tables(cyl8, saved, factorise)
            assert a.force_N == pytest.approx(force, rel=rtol)
            for measure in live.measures:
                np.testing.assert_allclose(a.receptors[measure], receptors[measure], rtol=rtol,
                                           atol=rtol * np.abs(receptors[measure]).max())
    assert a.force_N == pytest.approx(0.002, rel=1e-9)
    assert 0 < a.depth_mm < 3 and a.contact_area_mm2 > 0 and a.max_pressure_MPa > 0


def test_one_indentation_only(cyl8):
    live = LiveModel(cyl8)
    with pytest.raises(InputError, match="one indentation"):
        live.answer({"indentor": "C5", "depth_mm": [0.2, 0.4]})
    with pytest.raises(InputError, match="not-a-code|indentor"):
        live.answer({"indentor": "not-a-code", "depth_mm": [0.2]})


def test_afferents_need_a_pad(cyl8):
    live = LiveModel(cyl8)
    with pytest.raises(InputError, match="3D model"):
        live.scene_toml({"indentor": "C5", "depth_mm": [0.5]}, afferent_class="SA1")


def test_toml_values():
    assert toml_value('bar "x"\\') == '"bar \\"x\\"\\\\"'
    assert toml_value([1, 2.5, True]) == "[1, 2.5, true]"
    with pytest.raises(InputError, match="finite"):
        toml_value(float("inf"))


def count_sa1(model) -> int:
    """SA1 afferents a scene places over the whole pad of a model folder (the published density)."""
    from fem.io.modelfolder import CONTACT_REGION, read_model
    from fem.receptors.afferents import place
    m, _ = read_model(model)
    return len(place(m, m.surface_nodes(CONTACT_REGION[3]), ("SA1",)))


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def test_bad_input_is_refused_before_any_work(cyl8, tmp_path):
    watch = [cyl8, tmp_path]
    assert_refused(["explore", tmp_path / "nothing"], watch, "no mesh.vtu")
    assert_refused(["explore", cyl8, "--material", "m433310"], watch, "--material m433310 has 6 digits")
    assert_refused(["explore", cyl8, "--port", "0"], watch, "--port 0")
    assert_refused(["explore", cyl8, "--scenes", cyl8 / "mesh.vtu"], watch, "--scenes")
    with socket.socket() as busy:
        busy.bind(("127.0.0.1", 0))
        busy.listen()
        port = busy.getsockname()[1]
        assert_refused(["explore", cyl8, "--port", port], watch, "in use")


def test_without_the_extra_it_says_how_to_install(cyl8, tmp_path, monkeypatch):
    import importlib.util
    real = importlib.util.find_spec
    monkeypatch.setattr(importlib.util, "find_spec", lambda name, *a: None if name == "trame_vtk" else real(name, *a))
    assert_refused(["explore", cyl8], [cyl8, tmp_path], "pip install -e '.[explore]'")


def _wait(what, timeout_s=60.0):
    t0 = time.monotonic()
    while time.monotonic() - t0 < timeout_s:
        value = what()
        if value:
            return value
        time.sleep(0.05)
    raise AssertionError(f"timed out after {timeout_s} s")


@pytest.mark.slow
@pytest.mark.skipif(not (CHROMIUM.exists() and CHROMEDRIVER.exists()),
                    reason="needs Debian's chromium and chromium-driver (.ci/run installs them)")
def test_the_browser_shows_the_command_lines_force(tmp_path):
    pytest.importorskip("selenium")
    pytest.importorskip("trame")
    from selenium.webdriver.common.by import By
    from selenium.webdriver.common.keys import Keys
    model = tmp_path / "monkey"
    assert cli("mesh", "--preset", "monkey", "--size", "1.5", "--out", model, "--quiet").code == 0
    scenes, cwd = tmp_path / "scenes", tmp_path / "cwd"
    cwd.mkdir()
    before = snapshot(model)
    port = free_port()
    server = subprocess.Popen([sys.executable, str(ROOT / "pipeline.py"), "explore", str(model), "--port", str(port),
                               "--scenes", str(scenes), "--quiet"], cwd=cwd, stdout=subprocess.PIPE,
                              stderr=subprocess.PIPE, text=True, env={**os.environ, "PYTHONPATH": str(ROOT)})
    browser = None
    try:
        line = server.stdout.readline()
        assert f"http://127.0.0.1:{port}/" in line, (line, server.stderr.read() if server.poll() is not None else "")
        browser = headless_chromium()
        browser.get(f"http://127.0.0.1:{port}/")

        def text(ident):
            try:
                return browser.find_element(By.ID, ident).get_attribute("textContent").strip()
            except Exception:
                return ""

        def click(ident):                     # in the page's script: the drawer may scroll under the footer
            browser.execute_script("arguments[0].click()", browser.find_element(By.ID, ident))
        _wait(lambda: text("force-exact"))
        first = float(text("force-exact"))
        field = browser.find_element(By.ID, "value")
        field.send_keys(Keys.CONTROL, "a")
        field.send_keys("1.25")
        _wait(lambda: text("depth") == "1.25 mm")
        force = float(text("force-exact"))
        assert force > first > 0
        assert text("force").endswith(" N") and text("area").endswith("mm²") and text("pressure").endswith("MPa")
        click("save")
        _wait(lambda: text("saved").startswith("saved"))
        saved = scenes / "explorer_scene.toml"
        assert load_scene(saved).experiments[0].depth_mm == (1.25,)
        reference, _ = indent_tables(model, saved, factorise=False)
        assert force == pytest.approx(reference, rel=1e-9)
        click("fire")                   # SA1 under a ramp and hold
        spikes = int(_wait(lambda: text("spikes"), timeout_s=300))
        assert text("afferents").startswith(f"{count_sa1(model)} SA1 afferents")
        click("save-afferents")
        name = browser.find_element(By.ID, "scene-name")
        name.send_keys(Keys.CONTROL, "a")
        name.send_keys("afferents.toml")
        click("save")
        _wait(lambda: text("saved").endswith("afferents.toml"))
    finally:
        if browser is not None:
            browser.quit()
        server.terminate()
        server.wait(timeout=30)
    written = snapshot(model) - before
    assert written and all(Path(p).relative_to(model).parts[0] == "response" for p in written)
    assert not any(cwd.iterdir())
    assert sorted(p.name for p in scenes.iterdir()) == ["afferents.toml", "explorer_scene.toml"]
    shutil.rmtree(model / "response")
    run = tmp_path / "run"                      # the command line fires the same spikes
    assert cli("indent", model, "--scene", scenes / "afferents.toml", "--out", run, "--no-plots", "--quiet").code == 0
    table = np.genfromtxt(run / "experiment1" / "afferents.csv", delimiter=",", names=True, dtype=None,
                          encoding="utf-8")
    assert spikes > 0 and int(table["spikes"].sum()) == spikes
