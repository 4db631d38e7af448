"""The `render` job: a synthetic turntable set of a known shape, with its ground truth."""
from __future__ import annotations

from fem.geometry.presets import make_shape
from fingertip.errors import InputError
from fingertip.staging import holding
from reconstruct.synthetic import render_turntable


@holding()
def run_render(shape_name: str, out_dir, views: int = 100, span_deg: float = 360.0, size_px=(700, 900),
               mm_per_px: float = 0.04, aspect: float = 1.0, blur_px: float = 0.8, noise: float = 2.0,
               vignetting: float = 0.25, axis_offset_px: float = 0.0, tilt_deg: float = 0.0,
               rod: bool = True, groove: bool = False, seed: int = 0, progress: bool = False,
               camera_distance_mm: float | None = None, write_camera: bool = False,
               distortion: str | None = None, checkerboard: int = 0) -> str:
    """Render one of fem.geometry.presets.SHAPES into out_dir (images, turntable.toml, truth.json); returns
    the summary text. distortion: "K1" or "K1,K2" (radial Brown coefficients)."""
    k = None
    if distortion is not None:
        try:
            k = tuple(float(x) for x in distortion.split(","))
        except ValueError:
            k = ()
        if not 1 <= len(k) <= 2 or not all(abs(x) < 10 for x in k):
            raise InputError(f"--distortion must be K1 or K1,K2 (numbers, e.g. -0.05 or -0.05,0.1), not {distortion!r}")
    shape = make_shape(shape_name, groove=groove, rod=rod)
    truth = render_turntable(shape, out_dir, n_views=views, span_deg=span_deg, size_px=tuple(size_px),
                             mm_per_px=mm_per_px, aspect=aspect, blur_px=blur_px, noise=noise,
                             vignetting=vignetting, axis_offset_px=axis_offset_px, tilt_deg=tilt_deg,
                             seed=seed, progress=progress, camera_distance_mm=camera_distance_mm,
                             write_camera=write_camera, distortion=k, checkerboard=checkerboard)
    return (f"rendered {truth['views']} views of '{shape_name}' to {out_dir} "
            f"({truth['size_px'][0]} x {truth['size_px'][1]} px, {truth['mm_per_px']} mm/px, "
            f"{'camera %g mm from the axis' % camera_distance_mm if camera_distance_mm else 'parallel projection'}"
            f"{', lens distortion ' + distortion if distortion else ''}"
            f"{', %d checkerboard photos' % checkerboard if checkerboard else ''}); "
            f"ground truth in {out_dir}/truth.json")
