#!/usr/bin/env python
"""The explorer in a real browser: time from a control change to the updated numbers, picture and
plots, on the 3D presets; and a screenshot of each for the docs.

    python benchmarks/explorer_latency.py                         # monkey 1.0 mm and human 0.5 mm
    python benchmarks/explorer_latency.py monkey:1.0 --changes 20 --work out/explorer_bench

For each preset:size the model is meshed (cached) and prepared (`pipeline.py prepare`, timed, as
its own process with its peak memory), then `pipeline.py explore` runs as a subprocess and headless
Chromium (Debian's chromium and chromium-driver under Selenium) loads the page. Each change sets
one control the way the page's own widgets do (the trame state variable the control is bound to:
the depth, alternating with the position across the pad), and the browser is polled until

- numbers: the page shows the answer's number (its answer counter changed);
- picture: the server had rendered and pushed the pad's picture (`answered-at`, the server's clock,
  the same machine's as this script's);
- plots: the receptor map and profile of that answer are in the page.

Median and worst over the changes; the first change after loading is not counted (the page's
first picture). Polling costs a few ms per read. Writes benchmarks/results/explorer_latency.md and
docs/img/explorer_<preset>.png.
"""
from __future__ import annotations

import argparse
import json
import os
import resource
import shutil
import socket
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
from tests.helpers import headless_chromium  # noqa: E402


def run(*argv, cwd=ROOT) -> tuple[float, float]:
    """(seconds, peak resident GB of the child) of one pipeline.py command."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss
    t0 = time.perf_counter()
    subprocess.run([sys.executable, str(ROOT / "pipeline.py"), *map(str, argv)], cwd=cwd, check=True,
                   stdout=subprocess.DEVNULL)
    peak = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss
    return time.perf_counter() - t0, max(peak, before) / 2**20


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def measure(model: Path, changes: int, shot: Path) -> dict:
    """Latencies (s) of `changes` control changes in the browser, and a screenshot."""
    from selenium.webdriver.common.by import By
    port = free_port()
    server = subprocess.Popen([sys.executable, str(ROOT / "pipeline.py"), "explore", str(model), "--port", str(port),
                               "--scenes", str(model.parent / "scenes"), "--quiet"], stdout=subprocess.PIPE,
                              stderr=subprocess.DEVNULL, text=True)
    browser = None
    try:
        assert "http://" in server.stdout.readline()
        browser = headless_chromium()
        browser.get(f"http://127.0.0.1:{port}/")

        def text(ident):
            return browser.find_element(By.ID, ident).get_attribute("textContent").strip()

        def wait(ok, timeout_s=30.0):
            t0 = time.time()
            while time.time() - t0 < timeout_s:
                try:
                    if ok():
                        return time.time()
                except Exception:
                    pass
                time.sleep(0.002)
            raise TimeoutError(f"no answer in {timeout_s} s; error shown: {text('error') if browser else ''}")
        wait(lambda: text("force-exact"))
        pad = browser.execute_script("return [window.trame.state.get('x_mm'), window.trame.state.get('value')]")
        rows = []
        rng = np.random.default_rng(0)
        for k in range(changes + 1):
            n0 = int(text("answers"))
            key, value = ("value", round(float(rng.uniform(0.2, 1.5)), 2)) if k % 2 == 0 else \
                ("x_mm", round(float(pad[0] + rng.uniform(-1.5, 1.5)), 2))
            if browser.execute_script(f"return window.trame.state.get('{key}')") == value:
                value += 0.01                    # an equal value is no change
            t0 = time.time()
            browser.execute_script(f"window.trame.state.set('{key}', {value})")
            t_numbers = wait(lambda n0=n0: int(text("answers")) > n0)
            t_plots = wait(lambda n0=n0: int(text("drawn")) > n0)
            rows.append((t_numbers - t0, float(text("answered-at")) - t0, t_plots - t0,
                         float(text("answer-ms").split()[0]) / 1e3))
        browser.execute_script("window.trame.state.set('value', 1.0)")
        time.sleep(1.5)
        shot.parent.mkdir(parents=True, exist_ok=True)
        browser.save_screenshot(str(shot))
    finally:
        if browser is not None:
            browser.quit()
        server.terminate()
        server.wait(timeout=30)
    r = np.array(rows[1:])
    return {name: (float(np.median(r[:, i])), float(r[:, i].max()))
            for i, name in enumerate(("numbers", "picture", "plots", "answer"))}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("models", nargs="*", default=["monkey:1.0", "human:0.5"], help="preset:size (mm)")
    ap.add_argument("--changes", type=int, default=50)
    ap.add_argument("--work", default="out/explorer_bench")
    args = ap.parse_args(argv)
    lines = ["# Explorer latency in the browser", "",
             f"`python benchmarks/explorer_latency.py {' '.join(args.models)} --changes {args.changes}`; "
             f"{os.cpu_count()} cores. Seconds from a control change to what the page shows, median / worst "
             f"of {args.changes} changes (depth and position alternating).", "",
             "| model | DOFs | prepare s | prepare peak GB | answer | numbers | picture pushed | plots |",
             "|---|---|---|---|---|---|---|---|"]
    for spec in args.models:
        preset, size = spec.split(":")
        model = Path(args.work) / f"{preset}_{size}"
        if not (model / "mesh.vtu").exists():
            run("mesh", "--preset", preset, "--size", size, "--out", model, "--quiet")
        shutil.rmtree(model / "response", ignore_errors=True)          # a first build, timed
        prep_s, prep_gb = run("prepare", model, "--quiet")
        dofs = json.loads((model / "model.json").read_text())["mesh"]["sizing_achieved"]["dofs"]
        t = measure(model, args.changes, ROOT / "docs" / "img" / f"explorer_{preset}.png")
        cell = lambda k, t=t: f"{1e3 * t[k][0]:.0f} / {1e3 * t[k][1]:.0f} ms"
        lines.append(f"| {preset} {size} mm | {dofs} | {prep_s:.1f} | {prep_gb:.2f} | {cell('answer')} | "
                     f"{cell('numbers')} | {cell('picture')} | {cell('plots')} |")
        print(lines[-1], flush=True)
    out = ROOT / "benchmarks" / "results" / "explorer_latency.md"
    out.write_text("\n".join(lines) + "\n")
    print(f"-> {out}")


if __name__ == "__main__":
    main()
