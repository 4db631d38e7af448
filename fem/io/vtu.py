"""Export solutions: VTU with quadratic cells for ParaView, CSV of point samples. Writes are atomic.

    write_solution("static.vtu", sol, points=receptors)     # static.vtu + static.csv of samples

VTU: `tetra10` (3D) or `triangle6` (2D) cells on all P2 nodes; point data `displacement_mm`
(n, 3); cell data `layer`, `E_MPa`, `nu` and every measure of fem.core.measures.MEASURES evaluated
at the element centroid (cell data, so nothing is averaged across a layer interface). A finite
kinematics run's files hold the deformed geometry (points at their displaced positions) and the
measures of the finite state (`fields_mesh`).
"""
from __future__ import annotations

import csv
from pathlib import Path

import meshio
import numpy as np

from fingertip.staging import atomic_write

_VTK_CELL = {3: "tetra10", 2: "triangle6"}


def quadratic_cells(model) -> np.ndarray:
    """(M, 10) or (M, 6) P2 node ids per element in VTK order (vertices, then edge midpoints)."""
    return model.element_nodes.T


def write_vtu(path, solution) -> None:
    """Write `solution` (fem.core.fields.Solution) to a VTU file at `path`."""
    write_mesh(path, vtu_mesh(solution))


def write_solution(path, solution, points=None, names=None, layer=None) -> None:
    """A quadratic-cell VTU of `solution` at `path` and, with `points` (n, dim) mm, a CSV of the
    measures `names` (default all) sampled there beside it (same stem, `.csv`)."""
    write_vtu(path, solution)
    if points is not None:
        write_csv(Path(path).with_suffix(".csv"), points, solution.fields(points, names, layer))


def write_mesh(path, mesh) -> None:
    """Write a `vtu_mesh` to `path` (atomically; zlib-compressed by meshio, which releases the
    GIL while it compresses, so several files can be written from threads at once)."""
    atomic_write(path, lambda tmp: meshio.write(tmp, mesh, file_format="vtu"))


def vtu_mesh(solution):
    """meshio.Mesh of a `solution`: the P2 cells, displacement and the element fields."""
    return fields_mesh(solution.model, solution.u, solution.element_fields)


def fields_mesh(model, u, element_fields: dict, deformed: bool = False):
    """meshio.Mesh of a model's displacement u (ndof,) mm with cell data `element_fields` ({name:
    (M,)}); deformed: the points at their displaced positions (finite kinematics: the deformed
    geometry), else at rest."""
    disp = np.zeros((model.nnodes, 3))
    disp[:, :model.dim] = np.asarray(u, float).reshape(-1, model.dim)
    points = np.zeros((model.nnodes, 3))
    points[:, :model.dim] = model.nodes
    if deformed:
        points += disp
    E = np.vectorize(model.material.E_MPa.get, otypes=[float])(model.layer)
    nu = np.vectorize(model.material.nu.get, otypes=[float])(model.layer)
    cell_data = {"layer": model.layer.astype(np.int32), "E_MPa": E, "nu": nu, **element_fields}
    return meshio.Mesh(points, [(_VTK_CELL[model.dim], quadratic_cells(model))],
                       point_data={"displacement_mm": disp},
                       cell_data={k: [np.asarray(v)] for k, v in cell_data.items()})


def write_csv(path, points, columns: dict[str, np.ndarray]) -> None:
    """CSV with x_mm, y_mm, z_mm then one column per entry of `columns` ((n,) arrays)."""
    x = np.zeros((len(np.atleast_2d(points)), 3))
    p = np.atleast_2d(np.asarray(points, dtype=float))
    x[:, :p.shape[1]] = p[:, :3]

    def write(tmp):
        with open(tmp, "w", newline="") as fh:
            w = csv.writer(fh)
            w.writerow(["x_mm", "y_mm", "z_mm", *columns])
            for i in range(len(x)):
                w.writerow([*(f"{v:.6g}" for v in x[i]), *(f"{np.asarray(c)[i]:.9g}" for c in columns.values())])

    atomic_write(path, write)
