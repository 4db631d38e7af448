"""report.png: the diagnostics a user checks before trusting the sections (thesis figure 5-2 and more)."""
from __future__ import annotations

import textwrap

import numpy as np
from matplotlib.figure import Figure

from reconstruct.silhouette import extract_borders


def write_report(rec, path) -> None:
    """Six panels: the volar view with its extracted border and the axis; its grey-level histogram
    with the Otsu level and the 50 % level; section width and height along z; sections inside their
    tangent polygons; all sections seen from the side; the summary."""
    t, fr = rec.table, rec.frame
    i = int(np.argmin(np.abs(np.mod(t.angles_deg - t.volar_view_deg + 180, 360) - 180)))
    img = t.read(t.image_paths[i])
    if rec.turned_180:                               # show it as the stage saw it
        img = np.ascontiguousarray(img[::-1, ::-1])
    b = extract_borders(img, t.image_paths[i].name)

    fig = Figure(figsize=(15, 9.5))
    ax = fig.subplots(2, 3)
    a = ax[0, 0]
    a.imshow(img, cmap="gray", vmin=0, vmax=255)
    rows = np.arange(len(b.left_px))
    a.plot(b.left_px, rows, "r-", lw=0.8, label="border (50 % level)")
    a.plot(b.right_px, rows, "r-", lw=0.8)
    a.plot(fr.axis_col_px(rows.astype(float)), rows, "c--", lw=0.8, label="rotation axis")
    for z in (rec.z_mm[0], rec.z_mm[-1]):
        row = fr.height_px - 0.5 - (z + rec.z_offset_mm) / fr.scale.sy_mm
        a.axhline(row, color="y", lw=0.6)
    a.set_title(f"{t.image_paths[i].name}: border and axis (yellow: kept z range)", fontsize=9)
    a.set_xlabel("image column (px)"), a.set_ylabel("image row (px)")
    a.legend(fontsize=7, loc="lower right")

    a = ax[0, 1]
    a.hist(img.ravel(), bins=256, range=(0, 256), color="0.3", log=True)
    a.axvline(b.threshold, color="b", label=f"Otsu level {b.threshold:.0f}")
    a.axvline(0.5 * (b.background + b.object), color="r", ls="--",
              label=f"50 % level at the centre\n(background {b.background:.0f}, object {b.object:.0f};\n"
                    f"it follows the lighting)")
    a.set_xlabel("grey level"), a.set_ylabel("pixels")
    a.legend(fontsize=7, loc="upper center", framealpha=0.9)
    a.set_title("grey-level histogram of that view", fontsize=9)

    a = ax[0, 2]
    widths = [np.max(p[:, 0]) - np.min(p[:, 0]) for p in rec.sections]
    heights = [np.max(p[:, 1]) - np.min(p[:, 1]) for p in rec.sections]
    a.plot(rec.z_mm, widths, "o-", ms=3, label="section width (x)")
    a.plot(rec.z_mm, heights, "s-", ms=3, label="section height (y)")
    a.set_xlabel("z (mm)"), a.set_ylabel("mm"), a.legend(fontsize=7)
    a.set_title("section size along the finger; " + "; ".join(rec.trims) if rec.trims else "", fontsize=8)

    a = ax[1, 0]
    pick = np.unique(np.linspace(0, len(rec.z_mm) - 1, 4).round().astype(int))
    for k in pick:
        p, poly = rec.sections[k], rec.polygons[k]
        line, = a.plot(*np.vstack([p, p[:1]]).T, lw=1.2, label=f"z = {rec.z_mm[k]:.1f} mm")
        a.plot(*np.vstack([poly, poly[:1]]).T, lw=0.5, color=line.get_color(), alpha=0.6)
    a.plot(0, 0, "k+", ms=10)
    a.set_aspect("equal"), a.set_xlabel("x (mm)"), a.set_ylabel("y (mm, volar up)")
    a.legend(fontsize=7), a.set_title("sections (thick) inside their tangent polygons (thin)", fontsize=9)

    a = ax[1, 1]
    for z, p in zip(rec.z_mm, rec.sections):
        a.plot(p[:, 0], np.full(len(p), z), lw=0.3, color="0.4")
    a.set_xlabel("x (mm)"), a.set_ylabel("z (mm)")
    a.set_title(f"{len(rec.z_mm)} sections: spacing adapts to the shape", fontsize=9)

    a = ax[1, 2]
    a.axis("off")
    text = "\n".join(textwrap.fill(line, 70, subsequent_indent=" " * 16) for line in rec.summary().splitlines())
    a.text(0, 1, text, family="monospace", fontsize=7, va="top")
    fig.tight_layout()
    fig.savefig(path, dpi=80)
