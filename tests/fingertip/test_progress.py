"""Progress on stderr (silent with --quiet), the timing estimate, 2D summaries, PVD times, figure layout."""
import io
import re
import time
import xml.etree.ElementTree as ET

import numpy as np
import pytest
from matplotlib.backends.backend_agg import FigureCanvasAgg

import fingertip.progress
import pipeline
from fem import plots
from fem.experiments.runner import LARGE_DEFORMATION
from fingertip.progress import SILENT, Progress, TimingHistory, as_progress


@pytest.fixture(autouse=True)
def own_cache(tmp_path, monkeypatch):
    monkeypatch.setenv("FINGERTIP_CACHE_DIR", str(tmp_path / "cache"))


def test_power_law_estimate(tmp_path):
    h = TimingHistory(tmp_path / "t.json")
    assert h.estimate("factorise-3d", 1000) is None                      # no history: no estimate
    h.add("factorise-3d", 1e4, 2.0)
    assert h.estimate("factorise-3d", 2e4) == pytest.approx(4.0)         # one size: proportional
    h.add("factorise-3d", 1e5, 2.0 * 10 ** 1.5)                          # t ~ n^1.5
    # seconds are stored to 1 ms: 63.246 for 63.2456, so the fit is good to about 1e-5
    assert h.estimate("factorise-3d", 1e6) == pytest.approx(2.0 * 100 ** 1.5, rel=1e-4)
    assert h.estimate("pytetwild", 1e6) is None                          # kinds are separate
    (tmp_path / "t.json").write_text("{not json")                        # unreadable: empty history
    assert h.estimate("factorise-3d", 1e5) is None


def test_task_line_and_silence():
    stream = io.StringIO()
    p = Progress(stream=stream, history=None)
    with p.task("long call"):
        time.sleep(1.3)
    with p.task("short call"):
        pass
    p.note("a note")
    text = stream.getvalue()
    assert re.search(r"long call: done in 1\.\d s", text)
    assert "short call" not in text                                      # under a second: nothing
    assert text.endswith("a note\n")
    assert as_progress(None) is SILENT and as_progress(False) is SILENT
    assert list(SILENT.bar([1, 2])) == [1, 2]


def test_bars_show_only_after_a_delay():
    """A loop that ends (or is refused) within BAR_DELAY_S prints nothing; a longer one its bar."""
    stream = io.StringIO()
    p = Progress(stream=stream, history=None)
    assert list(p.bar(range(3), desc="quick")) == [0, 1, 2]
    assert stream.getvalue() == ""
    with pytest.raises(ValueError):
        for _ in p.bar(range(3), desc="refused"):
            raise ValueError("refused on the first item")
    assert stream.getvalue() == ""
    for _ in p.bar(range(2), desc="slow", delay=0.05):
        time.sleep(0.1)
    assert "slow" in stream.getvalue() and "2/2" in stream.getvalue()


def test_indent_progress_on_stderr_and_quiet(cyl8, tmp_path, capsys, monkeypatch):
    monkeypatch.setattr(fingertip.progress, "BAR_DELAY_S", 0.0)          # the bar at once, however quick
    args = ["indent", str(cyl8), "--indentor", "C5", "--depth", "0.25:1:0.25"]
    assert pipeline.main(args + ["--out", str(tmp_path / "a")]) == 0
    out, err = capsys.readouterr()
    assert "indentations" in err and "4/4" in err                        # the tqdm bar, on stderr
    assert "indentations:" not in out
    assert pipeline.main(args + ["--out", str(tmp_path / "b"), "--quiet"]) == 0
    out, err = capsys.readouterr()
    assert out == ""                             # quiet: no progress, no summary; the 1 mm step's validity warning stays
    assert err.splitlines() == ["warning: C5 at 1 mm: the linear displacement strains receptors by 0.30 (> 0.2) "
                                "(element inversion not checked: a stored response model has no full displacement "
                                "field): small-strain results are out of their range here; " + LARGE_DEFORMATION]


def test_force_control_summary_2d(cyl8, tmp_path, capsys):
    out_dir = tmp_path / "f"
    assert pipeline.main(["indent", str(cyl8), "--indentor", "C5", "--force", "0.002", "--out", str(out_dir)]) == 0
    out = capsys.readouterr().out
    assert str(out_dir) in out
    m = re.search(r"force 0\.002 N/mm reached at depth ([0-9.]+) mm", out)
    assert m, out
    with open(out_dir / "C5.csv") as fh:
        depth = float(fh.read().splitlines()[1].split(",")[3])
    assert float(m.group(1)) == pytest.approx(depth, rel=5e-3)           # printed with 3 digits
    assert " N," not in out and " N " not in out                          # no 3D unit for a 2D force
    assert not (out_dir / "C5_force.png").exists()                        # one indentation: no one-dot plot
    assert (out_dir / "C5_profile.png").is_file()


def _pvd_times(path):
    return [float(d.get("timestep")) for d in ET.parse(path).getroot().iter("DataSet")]


def test_pvd_timesteps_are_depths_and_offsets(cyl8, tmp_path):
    out = tmp_path / "d"
    assert pipeline.main(["indent", str(cyl8), "--indentor", "C5", "--depth", "0.25:1:0.25", "--pvd",
                          "--out", str(out), "--quiet"]) == 0
    assert _pvd_times(out / "C5.pvd") == [0.25, 0.5, 0.75, 1.0]
    files = [d.get("file") for d in ET.parse(out / "C5.pvd").getroot().iter("DataSet")]
    assert files == [f"C5_{i:03d}.vtu" for i in range(4)]
    out = tmp_path / "s"
    assert pipeline.main(["indent", str(cyl8), "--indentor", "bar:1.5", "--force", "0.001", "--sweep",
                          "x=-2:2:0.5", "--pvd", "--out", str(out), "--quiet"]) == 0    # within the 3 mm over the bone
    assert np.allclose(_pvd_times(out / "bar_1.5.pvd"), np.arange(-2, 2.001, 0.5))


def test_profile_figure_labels_inside_canvas(tmp_path):
    x = np.linspace(-4, 4, 81)
    results = [(f"{d:.2f} mm", -d * np.exp(-x ** 2), 1e-4 * np.maximum(0, 1 - x ** 2)) for d in (0.25, 1.0)]
    fig = plots.indent_profile_figure("C5", x, results)
    plots.save(fig, tmp_path / "p.png")
    FigureCanvasAgg(fig)
    renderer = fig.canvas.get_renderer()
    box = fig.bbox
    for ax in fig.axes:
        for text in (ax.yaxis.label, ax.xaxis.label, ax.title):
            if not text.get_text():
                continue
            e = text.get_window_extent(renderer)
            assert box.x0 - 0.5 <= e.x0 and e.x1 <= box.x1 + 0.5, text.get_text()
            assert box.y0 - 0.5 <= e.y0 and e.y1 <= box.y1 + 0.5, text.get_text()


def test_axis_labels_carry_units():
    assert plots.axis_label("max_pressure_MPa") == "max pressure, MPa"
    assert plots.axis_label("force_N", dim=2) == "force, N/mm"
    assert plots.axis_label("strain_yy").endswith(", -")
    assert plots.axis_label("contact_area_mm2", dim=2) == "contact area, mm (width)"
