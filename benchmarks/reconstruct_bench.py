"""Image stage: section error and wall time against number of views, image size and camera distance.

    python benchmarks/reconstruct_bench.py            # full table (renders into .cache/, a few minutes)
    python benchmarks/reconstruct_bench.py --quick    # smaller table

Renders the human parametric fingertip (blur 0.8 px, noise 2 grey levels, 25 % vignetting, axis
offset 6.4 px, tilt 0.7 deg, rod) and reconstructs it. Error: distance from reconstructed section
points to the true section, in px and um. Time: wall time of the stage without writing outputs
(reading images, silhouettes, calibration, sections, loft), on this machine's 2 cores.
Writes benchmarks/results/reconstruct_bench.md and .png.
"""
from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))

from fem.geometry.presets import make_shape, shape_from_truth  # noqa: E402
from reconstruct.pipeline import reconstruct, sections_document  # noqa: E402
from reconstruct.synthetic import compare_to_truth, load_truth, render_turntable  # noqa: E402
from reconstruct.turntable import load_turntable  # noqa: E402

SIZES = {"350x450 @ 80 um": ((350, 450), 0.08), "700x900 @ 40 um": ((700, 900), 0.04),
         "1400x1800 @ 20 um": ((1400, 1800), 0.02)}


def run(views: int, size: str, cache: Path, repeats: int = 2, camera_mm: float | None = None,
        key: bool = True) -> dict:
    """One row: camera_mm renders with a pinhole camera that far from the axis; key: give
    camera_distance_mm to the reconstruction (else it sees a parallel-projection manifest)."""
    size_px, mm = SIZES[size]
    folder = cache / (f"ft_{views}_{size_px[0]}x{size_px[1]}" + (f"_cam{camera_mm:g}" if camera_mm else ""))
    if not (folder / "truth.json").exists():
        render_turntable(make_shape("fingertip"), folder, n_views=views, size_px=size_px, mm_per_px=mm,
                         axis_offset_px=6.4 * 0.04 / mm, tilt_deg=0.7, seed=views, camera_distance_mm=camera_mm)
    manifest = folder / "turntable.toml"
    text = "".join(line + "\n" for line in manifest.read_text().splitlines() if "camera" not in line)
    manifest.write_text(text + (f"camera_distance_mm = {camera_mm!r}\n" if camera_mm and key else ""))
    best, cpu = np.inf, np.inf
    for _ in range(repeats):                    # best of n: the machine may be shared
        t0, c0 = time.perf_counter(), time.process_time()
        rec = reconstruct(load_turntable(folder))
        best, cpu = min(best, time.perf_counter() - t0), min(cpu, time.process_time() - c0)
    truth = load_truth(folder)
    err = compare_to_truth(sections_document(rec), shape_from_truth(truth), truth)
    vol = rec.surface.volume / err["true_volume_mm3"] - 1
    camera = "parallel" if camera_mm is None else f"{camera_mm:g} mm" + ("" if key else " (no key)")
    warned = next((w.split("by up to ")[1].split(";")[0] for w in rec.warnings if "by up to" in w), "")
    return dict(views=views, size=size, camera=camera, mean_px=err["mean_px"], max_px=err["max_px"],
                mean_um=err["mean_mm"] * 1e3, max_um=err["max_mm"] * 1e3, volume_pct=100 * vol,
                z0_px=err["z_shift_mm"] / mm, sections=len(rec.z_mm), time_s=best, cpu_s=cpu, warned=warned)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="only the 350x450 images and 700x900 at 100 views")
    args = ap.parse_args()
    cache = HERE.parent / ".cache" / "bench_reconstruct"
    small = "350x450 @ 80 um"
    cases = [(v, small, None, True) for v in (8, 25, 50, 100, 200)] + [(100, "700x900 @ 40 um", None, True)]
    if not args.quick:
        cases += [(v, "700x900 @ 40 um", None, True) for v in (8, 25, 50, 200)]
        cases += [(100, "1400x1800 @ 20 um", None, True)]
    cases += [(v, small, d, True) for d in (60.0, 120.0, 250.0, 500.0) for v in (36, 100)]
    cases += [(100, small, d, False) for d in (60.0, 120.0, 250.0, 500.0)]
    rows = []
    head = f"{'views':>5}  {'image':<18} {'camera':<17} {'mean px':>8} {'max px':>7} {'mean um':>8} " \
           f"{'max um':>7} {'vol %':>6} {'z0 px':>6} {'sect':>4} {'wall s':>7} {'cpu s':>6}  warned"
    print(f"cores: {os.cpu_count()}\n{head}")
    for v, size, d, key in cases:
        r = run(v, size, cache, camera_mm=d, key=key)
        rows.append(r)
        print(f"{r['views']:>5}  {r['size']:<18} {r['camera']:<17} {r['mean_px']:>8.3f} {r['max_px']:>7.3f} "
              f"{r['mean_um']:>8.2f} {r['max_um']:>7.2f} {r['volume_pct']:>+6.2f} {r['z0_px']:>+6.2f} "
              f"{r['sections']:>4} {r['time_s']:>7.2f} {r['cpu_s']:>6.2f}  {r['warned']}", flush=True)
    out = HERE / "results"
    out.mkdir(exist_ok=True)
    md = ["# Image stage: error and time against views and image size", "",
          "Human parametric fingertip, blur 0.8 px, noise 2 grey levels, 25 % vignetting, axis offset and "
          "tilt, rod. Error = distance from section points to the true section. Time = wall time of "
          f"`reconstruct()` (best of 2) on {os.cpu_count()} cores, without writing outputs; CPU = process "
          "time summed over both threads (what the run costs when the machine is shared). Camera: "
          "parallel projection, or a pinhole camera that far from the rotation axis, with "
          "`camera_distance_mm` in the manifest or without it (no key: the stage warns when it estimates "
          "an error above 0.5 px, column *warned*: sections and z = 0). z0 px: where z = 0 lies against "
          "the true proximal cut.", "",
          "| views | image | camera | mean px | max px | mean um | max um | volume % | z0 px | sections | "
          "wall s | CPU s | warned |",
          "|---:|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|"]
    md += [f"| {r['views']} | {r['size']} | {r['camera']} | {r['mean_px']:.3f} | {r['max_px']:.3f} | "
           f"{r['mean_um']:.2f} | {r['max_um']:.2f} | {r['volume_pct']:+.2f} | {r['z0_px']:+.2f} | "
           f"{r['sections']} | {r['time_s']:.2f} | {r['cpu_s']:.2f} | {r['warned']} |" for r in rows]
    (out / "reconstruct_bench.md").write_text("\n".join(md) + "\n")

    from matplotlib.figure import Figure

    fig = Figure(figsize=(10, 4))
    ax = fig.subplots(1, 2)
    for size in SIZES:
        rs = [r for r in rows if r["size"] == size and r["camera"] == "parallel"]
        if len(rs) > 1:
            v = [r["views"] for r in rs]
            ax[0].loglog(v, [r["mean_px"] for r in rs], "o-", label=f"{size} mean")
            ax[0].loglog(v, [r["max_px"] for r in rs], "s--", label=f"{size} max")
            ax[1].plot(v, [r["time_s"] for r in rs], "o-", label=size)
    ax[0].axhline(0.25, color="k", lw=0.5), ax[0].axhline(1.0, color="k", lw=0.5)
    ax[0].set_xlabel("views"), ax[0].set_ylabel("section error (px)"), ax[0].legend(fontsize=7)
    ax[1].set_xlabel("views"), ax[1].set_ylabel("wall time (s)"), ax[1].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(out / "reconstruct_bench.png", dpi=90)
    print(f"wrote {out / 'reconstruct_bench.md'} and .png")


if __name__ == "__main__":
    main()
