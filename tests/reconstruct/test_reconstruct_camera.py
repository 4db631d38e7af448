"""Image stage under a pinhole camera (reconstruct.camera) and the consistency checks
(reconstruct.checks), on a set rendered in perspective 120 mm from the axis (a macro lens).

Acceptance: with camera_distance_mm in the manifest, mean <= 0.25 px and max <= 1 px against the
true convex sections, volume within 1 %, z = 0 at the proximal cut within 1 px. Without it, a
warning with the estimated error and no inconsistent section. 48 views of 360 x 460 px at
0.08 mm/px keep the render to a few seconds; errors are in px, so they carry over to larger images.
"""
import shutil

import numpy as np
import pytest

import pipeline
from fem.geometry.presets import make_shape, shape_from_truth
from fingertip.errors import InputError
from reconstruct.checks import consistent_sections, fold_depth
from reconstruct.pipeline import reconstruct, sections_document
from reconstruct.sections import support_curve
from reconstruct.synthetic import compare_to_truth, load_truth, render_turntable
from reconstruct.turntable import load_turntable

SMALL = dict(size_px=(360, 460), mm_per_px=0.08, blur_px=0.8, noise=2.0, vignetting=0.25)


@pytest.fixture(scope="module")
def macro(tmp_path_factory):
    folder = tmp_path_factory.mktemp("macro") / "set"
    render_turntable(make_shape("fingertip"), folder, n_views=48, camera_distance_mm=120.0,
                     write_camera=True, **SMALL)
    return folder


def _errors(folder):
    rec = reconstruct(load_turntable(folder))
    doc = sections_document(rec)
    truth = load_truth(folder)
    return rec, doc, compare_to_truth(doc, shape_from_truth(truth), truth)


def test_render_writes_the_camera_only_when_asked(macro, tmp_path):
    assert "camera_distance_mm = 120.0" in (macro / "turntable.toml").read_text()
    assert load_truth(macro)["camera_distance_mm"] == 120.0
    code = pipeline.main(["render", "sphere", "--out", str(tmp_path / "r"), "--views", "4", "--size", "64", "80",
                          "--mm-per-px", "0.3", "--camera-distance-mm", "200", "--quiet"])
    assert code == 0 and "camera" not in (tmp_path / "r" / "turntable.toml").read_text()


def test_perspective_set_with_camera_distance_meets_targets(macro):
    rec, doc, err = _errors(macro)
    assert err["mean_px"] <= 0.25, err
    assert err["max_px"] <= 1.0, err
    assert abs(rec.surface.volume / err["true_volume_mm3"] - 1) <= 0.01
    assert abs(err["z_shift_mm"]) <= 1.0 * SMALL["mm_per_px"]          # z = 0 at the proximal cut
    assert not rec.warnings, rec.warnings
    assert all(fold_depth(np.array(s["points"])) < 1e-4 for s in doc["sections"])


def test_perspective_set_without_camera_distance_warns_and_stays_consistent(macro, tmp_path):
    folder = tmp_path / "set"
    shutil.copytree(macro, folder)
    toml = folder / "turntable.toml"
    toml.write_text("".join(l + "\n" for l in toml.read_text().splitlines() if "camera" not in l))
    rec, doc, err = _errors(folder)
    note = [w for w in rec.warnings if "camera_distance_mm" in w]
    assert len(note) == 1, rec.warnings
    # the camera found from the views and the error it predicts are close to the truth
    assert "about 120 mm" in note[0]
    predicted = float(note[0].split("by up to ")[1].split(" px")[0])
    assert 0.5 * err["max_px"] <= predicted <= 2.0 * err["max_px"], (predicted, err)
    # whatever is written is a consistent stack of convex sections
    z = np.array([s["z"] for s in doc["sections"]])
    pts = np.array([s["points"] for s in doc["sections"]])
    assert all(fold_depth(p) < 1e-4 for p in pts)          # convex to rounding
    keep, msg = consistent_sections(z, pts, np.zeros(len(z)), SMALL["mm_per_px"])
    assert keep.all() and msg is None
    # the parallel projection is far off here: the camera model is what makes it accurate
    assert err["max_px"] > 1.0


@pytest.mark.parametrize("distance", [60.0, 500.0])
def test_proximal_cut_and_parallel_warning_at_other_distances(distance, tmp_path):
    """z = 0 within 1 px of the cut with the key at 60 and 500 mm (the rim of the cut is seen
    up to 30 px below it at 60 mm); without the key, a warning at 60 mm that names the distance,
    the error and the key, and none at 500 mm, where a parallel projection errs by < 0.5 px."""
    folder = tmp_path / "set"
    render_turntable(make_shape("fingertip"), folder, n_views=36, camera_distance_mm=distance,
                     write_camera=True, seed=3, **SMALL)
    rec, doc, err = _errors(folder)
    assert abs(err["z_shift_mm"]) <= 1.0 * SMALL["mm_per_px"], err["z_shift_mm"] / SMALL["mm_per_px"]
    assert not [w for w in rec.warnings if "camera_distance_mm" in w], rec.warnings
    toml = folder / "turntable.toml"
    toml.write_text("".join(l + "\n" for l in toml.read_text().splitlines() if "camera" not in l))
    rec, doc, err = _errors(folder)
    note = [w for w in rec.warnings if "camera_distance_mm" in w]
    if distance >= 500:
        assert not note and err["max_px"] < 0.6, (note, err)
    else:
        assert len(note) == 1 and "about 60 mm" in note[0] and "z = 0 by" in note[0], note
        predicted = float(note[0].split("by up to ")[1].split(" px")[0])
        assert predicted > 1.0 and err["max_px"] > 1.0


def test_huge_camera_distance_is_the_parallel_projection(tmp_path):
    folder = tmp_path / "par"
    render_turntable(make_shape("sphere"), folder, n_views=36, size_px=(200, 260), mm_per_px=0.16)
    ortho = sections_document(reconstruct(load_turntable(folder)))
    with open(folder / "turntable.toml", "a") as f:
        f.write("camera_distance_mm = 1e7\n")
    far = sections_document(reconstruct(load_turntable(folder)))
    a = np.array([s["points"] for s in ortho["sections"]])
    # the pinhole path starts its sections past the blurred corner, so compare at equal z
    zs_o = np.array([s["z"] + ortho["calibration"]["z_offset_mm"] for s in ortho["sections"]])
    for s in far["sections"][1:-1]:
        zf = s["z"] + far["calibration"]["z_offset_mm"]
        i = int(np.argmin(np.abs(zs_o - zf)))
        if abs(zs_o[i] - zf) < 1e-6:
            assert np.abs(np.array(s["points"]) - a[i]).max() < 0.02 * 0.16     # 0.02 px
    assert not ortho["warnings"]


def test_folded_or_jumping_sections_are_trimmed_at_the_ends_and_refused_inside():
    coef = np.zeros((9, 9))
    coef[0] = 5.0
    curves = support_curve(coef, 360)                                       # 9 circles of radius 5
    z = np.arange(9.0)
    assert consistent_sections(z, curves, np.full(9, 0.05), 0.08) == (pytest.approx(np.ones(9, bool)), None)
    bad = np.full(9, 0.05)
    bad[0] = 5.0                                                            # tangents disagree
    keep, msg = consistent_sections(z, curves, bad, 0.08)
    assert not keep[0] and keep[1:].all() and "z 0.00 .. 0.00 mm" in msg
    big = curves.copy()
    big[8] *= 1.5                                                           # size jump at the tip
    keep, msg = consistent_sections(z, big, np.full(9, 0.05), 0.08)
    assert not keep[8] and keep[:8].all() and "size jumps" in msg
    big = curves.copy()
    big[4] *= 1.5
    with pytest.raises(InputError, match="z 4.00 mm"):
        consistent_sections(z, big, np.full(9, 0.05), 0.08)
    # a swallowtail: the outline runs back inside its own hull
    t = np.linspace(0, 2 * np.pi, 400, endpoint=False)
    tail = np.column_stack([np.cos(t), np.sin(t)]) * 5
    tail[100:120] *= 0.8
    assert fold_depth(tail) > 0.9 and fold_depth(curves[0]) < 1e-9


# --- lens calibration from a checkerboard/ folder -------------------------------------------

@pytest.fixture(scope="module")
def distorted(tmp_path_factory):
    """36 views at 120 mm through a lens with barrel distortion k1 = -0.05, 8 board photos,
    no camera_distance_mm: the distance comes from the calibrated focal length."""
    folder = tmp_path_factory.mktemp("lens") / "set"
    render_turntable(make_shape("fingertip"), folder, n_views=36, camera_distance_mm=120.0,
                     distortion=(-0.05,), checkerboard=8, **SMALL)
    return folder


def test_checkerboard_lens_calibration_meets_targets(distorted):
    from reconstruct.lens import Lens

    assert "checkerboard_inner_corners = [9, 6]" in (distorted / "turntable.toml").read_text()
    rec, doc, err = _errors(distorted)
    assert err["mean_px"] <= 0.25, err
    assert err["max_px"] <= 1.0, err
    assert abs(rec.surface.volume / err["true_volume_mm3"] - 1) <= 0.01
    assert abs(err["z_shift_mm"]) <= 1.0 * SMALL["mm_per_px"]
    assert not rec.warnings, rec.warnings
    cam = doc["calibration"]
    assert "checkerboard focal length" in cam["camera_distance_source"] and "checkerboard" in rec.summary()
    truth = load_truth(distorted)
    true_k = np.array(truth["camera_matrix"])
    # a narrow field of view (about 14 deg) pins the focal length to a few 0.1 % and the
    # principal point to a few px with 8 photos; the distance follows from the focal length
    assert abs(cam["camera_distance_mm"] / 120.0 - 1) <= 0.01
    assert abs(cam["camera_matrix_px"][0][0] / true_k[0, 0] - 1) <= 0.01
    assert np.abs(np.array(cam["camera_matrix_px"])[:2, 2] - true_k[:2, 2]).max() <= 4.0
    assert cam["lens_rms_px"] < 0.2 and cam["lens_photos"] == 8
    # what matters is the undistortion: over the whole image it is within 0.25 px of the true lens
    # (k1 = -0.05 moves the corners by 0.5 px; k1 and k2 alone trade off against each other)
    fitted = Lens(np.array(cam["camera_matrix_px"]), np.array(cam["distortion"]), 0.0, 8, (360, 460))
    true = Lens(true_k, np.array([-0.05, 0, 0, 0, 0]), 0.0, 8, (360, 460))
    c, r = np.meshgrid(np.linspace(0, 359, 13), np.linspace(0, 459, 15))
    a, b = np.array(fitted.undistort(c.ravel(), r.ravel())), np.array(true.undistort(c.ravel(), r.ravel()))
    assert np.abs(a - b).max() <= 0.25
    assert np.abs(np.array(true.undistort(c.ravel(), r.ravel())) - [c.ravel(), r.ravel()]).max() > 0.4


def test_distort_and_undistort_are_inverse():
    from reconstruct.lens import Lens

    lens = Lens(np.array([[900.0, 0, 170], [0, 910, 240], [0, 0, 1]]), np.array([-0.2, 0.1, 1e-3, -2e-3, 0]),
                0.0, 5, (360, 460))
    c, r = np.meshgrid(np.linspace(0, 359, 7), np.linspace(0, 459, 9))
    back = lens.distort(*lens.undistort(c.ravel(), r.ravel()))
    assert np.abs(np.array(back) - [c.ravel(), r.ravel()]).max() < 1e-6


def test_checkerboard_folder_errors(tmp_path, capsys):
    import cv2

    from reconstruct.lens import Lens
    from reconstruct.synthetic import render_checkerboards

    folder = tmp_path / "s"
    render_turntable(make_shape("sphere"), folder, n_views=8, size_px=(200, 260), mm_per_px=0.16)
    toml = folder / "turntable.toml"
    base = toml.read_text()

    def fails(*words):
        code = pipeline.main(["reconstruct", str(folder), "--out", str(tmp_path / "out"), "--quiet"])
        err = capsys.readouterr().err.strip()
        assert code == 2 and err.startswith("error:") and "\n" not in err, err
        assert all(w in err for w in words), err
        assert not (tmp_path / "out").exists()

    toml.write_text(base + "checkerboard_square_mm = 3.0\n")
    fails("checkerboard_square_mm", "no checkerboard/ folder")
    (folder / "checkerboard").mkdir()
    lens = Lens(np.array([[750.0, 0, 99.5], [0, 750, 129.5], [0, 0, 1]]), np.zeros(5), 0.0, 0, (200, 260))
    photos = render_checkerboards(lens, 6, (9, 6), 3.0, 120.0)
    for i, img in enumerate(photos[:4]):
        cv2.imwrite(str(folder / "checkerboard" / f"board_{i}.png"), img)
    fails("checkerboard_inner_corners", "[9, 6]")
    toml.write_text(base + "checkerboard_square_mm = 3.0\ncheckerboard_inner_corners = [9, 6]\n")
    fails("only 4 photo", "at least 5")
    cv2.imwrite(str(folder / "checkerboard" / "board_4.png"), np.full((260, 200), 200, np.uint8))
    fails("board_4.png", "checkerboard_inner_corners")
    cv2.imwrite(str(folder / "checkerboard" / "board_4.png"), np.full((100, 100), 200, np.uint8))
    fails("board_4.png", "100x100")
