"""Loft axial sections into a closed, outward-oriented, watertight triangle surface."""
from __future__ import annotations

import numpy as np
import trimesh


def resample_polar(points: np.ndarray, n: int) -> np.ndarray:
    """(n, 2) points of a convex CCW polygon at n uniform polar angles about its centroid,
    starting at angle 0 (so neighbouring sections correspond point by point)."""
    c = points.mean(axis=0)
    closed = np.vstack([points, points[:1]]) - c
    ang = np.unwrap(np.arctan2(closed[:, 1], closed[:, 0]))
    rad = np.linalg.norm(closed, axis=1)
    # radius along each ray by interpolating the polygon edge crossed (1/r is linear in a
    # straight edge only approximately; points are dense, so linear in angle is enough)
    target = ang[0] + np.mod(np.linspace(0.0, 2 * np.pi, n, endpoint=False) - ang[0], 2 * np.pi)
    r = np.interp(target, ang, rad)
    return c + np.column_stack([r * np.cos(target), r * np.sin(target)])


def loft(z_mm: np.ndarray, sections: list[np.ndarray], n_around: int = 180) -> trimesh.Trimesh:
    """Closed surface through sections (each (k, 2) CCW, convex) at axial positions z_mm (m,).

    Side walls join corresponding points of neighbouring sections; both ends are capped with a
    fan around the section centroid. Outward normals; vertices in mm.
    """
    rings = np.stack([resample_polar(np.asarray(p, float), n_around) for p in sections])
    m, n = rings.shape[:2]
    verts = np.column_stack([rings.reshape(-1, 2), np.repeat(z_mm, n)])
    i = np.arange(n)
    j = (i + 1) % n
    faces = []
    for k in range(m - 1):
        a, b = k * n + i, k * n + j
        c, d = (k + 1) * n + i, (k + 1) * n + j
        faces += [np.column_stack([a, b, d]), np.column_stack([a, d, c])]
    lo_c, hi_c = len(verts), len(verts) + 1
    verts = np.vstack([verts, [*rings[0].mean(axis=0), z_mm[0]], [*rings[-1].mean(axis=0), z_mm[-1]]])
    faces += [np.column_stack([np.full(n, lo_c), j, i]),
              np.column_stack([np.full(n, hi_c), (m - 1) * n + i, (m - 1) * n + j])]
    mesh = trimesh.Trimesh(verts, np.vstack(faces), process=False)
    if mesh.volume < 0:
        mesh.invert()
    return mesh
