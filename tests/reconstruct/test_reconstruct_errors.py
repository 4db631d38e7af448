"""Bad input to the image stage: one-line error, exit code 2, no traceback, nothing written."""
import shutil

import cv2
import numpy as np
import pytest

import pipeline
from fem.geometry.presets import make_shape
from reconstruct.synthetic import render_turntable

SMALL = dict(size_px=(200, 260), mm_per_px=0.16, blur_px=0.8, noise=2.0, n_views=24)


@pytest.fixture(scope="module")
def good(tmp_path_factory):
    folder = tmp_path_factory.mktemp("good") / "set"
    render_turntable(make_shape("fingertip"), folder, **SMALL)
    return folder


def _copy(good, tmp_path):
    dst = tmp_path / "set"
    shutil.copytree(good, dst)
    return dst


def _views(folder):
    return sorted(p for p in folder.glob("view_*.png"))


def _fails(folder, capsys, tmp_path, *words):
    out = tmp_path / "out"
    code = pipeline.main(["reconstruct", str(folder), "--out", str(out), "--quiet"])
    err = capsys.readouterr().err.strip()
    assert code == 2
    assert err.startswith("error: ") and "\n" not in err and "Traceback" not in err
    for w in words:
        assert w in err, err
    assert not out.exists()
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".out")]   # no staging left
    return err


def test_good_set_runs(good, tmp_path):
    assert pipeline.main(["reconstruct", str(good), "--out", str(tmp_path / "o"), "--quiet"]) == 0


def test_missing_folder(tmp_path, capsys):
    _fails(tmp_path / "nope", capsys, tmp_path, "does not exist")


def test_empty_folder(tmp_path, capsys):
    (tmp_path / "empty").mkdir()
    _fails(tmp_path / "empty", capsys, tmp_path, "no images")


def test_no_calibration_image(good, tmp_path, capsys):
    f = _copy(good, tmp_path)
    (f / "calibration.png").unlink()
    _fails(f, capsys, tmp_path, "calibration")


def test_unreadable_file(good, tmp_path, capsys):
    f = _copy(good, tmp_path)
    _views(f)[3].write_bytes(b"not a png at all")
    _fails(f, capsys, tmp_path, "cannot read", _views(f)[3].name)


def test_mixed_image_sizes(good, tmp_path, capsys):
    f = _copy(good, tmp_path)
    p = _views(f)[5]
    cv2.imwrite(str(p), cv2.resize(cv2.imread(str(p), 0), (180, 260)))
    _fails(f, capsys, tmp_path, "differ in size")


def test_no_object_in_a_view(good, tmp_path, capsys):
    f = _copy(good, tmp_path)
    p = _views(f)[7]
    cv2.imwrite(str(p), np.full((260, 200), 240, np.uint8))
    _fails(f, capsys, tmp_path, "no object", p.name)


def test_object_cut_by_the_frame_on_every_row(good, tmp_path, capsys):
    f = _copy(good, tmp_path)
    for p in _views(f):
        img = cv2.imread(str(p), 0)
        img[:, :70] = 20                       # a dark band on the left reaches every row
        img[:, 60:75] = 20
        cv2.imwrite(str(p), img)
    _fails(f, capsys, tmp_path, "frame")


def test_angles_missing(good, tmp_path, capsys):
    f = _copy(good, tmp_path)
    (f / "turntable.toml").unlink()
    _views(f)[2].rename(f / "view_two.png")
    _fails(f, capsys, tmp_path, "no view angle", "view_two.png")


def test_angles_duplicated(good, tmp_path, capsys):
    f = _copy(good, tmp_path)
    (f / "turntable.toml").write_text('[angles]\n' + "".join(
        f'"{p.name}" = {0.0 if i < 2 else 15.0 * i}\n' for i, p in enumerate(_views(f))))
    _fails(f, capsys, tmp_path, "duplicated")


def test_less_than_180_degrees(good, tmp_path, capsys):
    f = _copy(good, tmp_path)
    (f / "turntable.toml").write_text("start_deg = 0\nstep_deg = 5\n")     # 24 views: 120 deg
    _fails(f, capsys, tmp_path, "180")


def test_template_not_a_disc(good, tmp_path, capsys):
    f = _copy(good, tmp_path)
    img = np.full((260, 200), 240, np.uint8)
    img[60:160, 50:150] = 20                  # a square
    cv2.imwrite(str(f / "calibration.png"), img)
    _fails(f, capsys, tmp_path, "not show a disc")


def test_bad_manifest_and_options(good, tmp_path, capsys):
    f = _copy(good, tmp_path)
    (f / "turntable.toml").write_text("step_deg = 15\nzoom = 3\n")
    _fails(f, capsys, tmp_path, "unknown key")
    (f / "turntable.toml").write_text("step_deg = 15\n")
    code = pipeline.main(["reconstruct", str(f), "--out", str(tmp_path / "out"), "--spacing-mm", "2", "1"])
    assert code == 2 and "spacing" in capsys.readouterr().err
    code = pipeline.main(["reconstruct", str(f), "--out", str(tmp_path / "out"), "--tip-fraction", "-1"])
    assert code == 2 and not (tmp_path / "out").exists()


def test_wrong_manifest_types_name_the_key(good, tmp_path, capsys):
    f = _copy(good, tmp_path)
    for text, words in (('start_deg = "zero"\nstep_deg = 15\n', ("start_deg", "a number", "'zero'")),
                        ('step_deg = 15\naxis = 3\n', ("axis", "text")),
                        ('step_deg = 15\ncamera_distance_mm = "far"\n', ("camera_distance_mm", "number")),
                        ('step_deg = 15\ncamera_distance_mm = -5\n', ("camera_distance_mm", "positive")),
                        ('step_deg = 15\ncheckerboard_inner_corners = [9]\n', ("checkerboard_inner_corners",))):
        (f / "turntable.toml").write_text(text)
        _fails(f, capsys, tmp_path, *words)


@pytest.mark.parametrize("command", ["reconstruct", "render"])
def test_unusable_output_location_is_refused_first(good, tmp_path, capsys, command):
    afile = tmp_path / "afile"
    afile.write_text("x")
    args = [str(good)] if command == "reconstruct" else ["sphere"]
    for out, words in ((afile, ("existing file",)), ("/proc/x", ("cannot be created",))):
        code = pipeline.main([command, *args, "--out", str(out)])
        err = capsys.readouterr().err.strip()
        assert code == 2 and err.startswith("error: --out") and "\n" not in err, err
        assert all(w in err for w in words)
    assert afile.read_text() == "x" and sorted(p.name for p in tmp_path.iterdir()) == ["afile"]


def test_no_progress_before_an_error_and_summary_names_the_folder(good, tmp_path, capsys):
    f = _copy(good, tmp_path)
    cv2.imwrite(str(_views(f)[0]), np.full((260, 200), 240, np.uint8))
    code = pipeline.main(["reconstruct", str(f), "--out", str(tmp_path / "out")])   # progress on
    err = capsys.readouterr().err
    assert code == 2 and err.count("error:") == 1 and err.strip().splitlines()[-1].startswith("error: ")
    assert "silhouettes" not in err, err
    code = pipeline.main(["reconstruct", str(good), "--out", str(tmp_path / "ok")])
    out = capsys.readouterr().out
    assert code == 0 and f"written to      {tmp_path / 'ok'}/" in out


def test_finger_running_off_the_side_names_the_image(tmp_path, capsys):
    """Zoomed in so far that the finger leaves the image on most rows of a view (was an IndexError
    in reconstruct.pipeline._trim): refused naming the image and what to do."""
    folder = tmp_path / "zoomed"
    render_turntable(make_shape("fingertip"), folder, **{**SMALL, "mm_per_px": 0.085})
    err = _fails(folder, capsys, tmp_path, "the finger touches the left image frame of view_000", "zoom out")
    assert "internal error" not in err


def test_truncated_jpeg_is_refused_before_decoding(tmp_path, capfd):
    """A truncated JPEG: one line naming it, no libjpeg noise (checked on the file descriptor)."""
    folder = tmp_path / "jpg"
    render_turntable(make_shape("fingertip"), folder, **SMALL, image_format="jpg")
    victim = sorted(folder.glob("view_*.jpg"))[3]
    victim.write_bytes(victim.read_bytes()[:-len(victim.read_bytes()) // 2])
    out = tmp_path / "out"
    code = pipeline.main(["reconstruct", str(folder), "--out", str(out), "--quiet"])
    err = capfd.readouterr().err.strip()
    assert code == 2 and err.count("\n") == 0, err
    assert err.startswith("error: image") and victim.name in err and "truncated" in err
    assert not out.exists()


def test_dotfiles_are_not_views(good, tmp_path):
    """macOS `._view_000.png` resource forks (and any dotfile) in the folder are ignored."""
    from reconstruct.turntable import load_turntable

    f = _copy(good, tmp_path)
    first = _views(f)[0]
    (f / f"._{first.name}").write_bytes(b"\x00\x05\x16\x07 AppleDouble")
    (f / ".hidden_012.0deg.png").write_bytes(first.read_bytes())
    table = load_turntable(f)
    assert [p.name for p in table.image_paths] == [p.name for p in _views(f)]
    assert pipeline.main(["reconstruct", str(f), "--out", str(tmp_path / "o"), "--quiet"]) == 0
