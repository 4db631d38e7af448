"""The explorer's 3D picture: the contact candidates' surface (each P2 triangle split into four
flat ones; in 2D, the section's pad as segments) moved by its deflection along the approach and
coloured by pressure or deflection, over the undeformed body's outline, in a pyvista plotter that
renders off screen (the browser receives images: no WebGL needed)."""
from __future__ import annotations

import numpy as np

from fem.io.modelfolder import CONTACT_REGION
from fem.io.runfolder import pad3

COLOURS = {"pressure_MPa": "pressure [MPa]", "deflection_mm": "deflection [mm]"}
"""Surface-table columns the pad can be coloured by, with their colour-bar titles."""
SPLIT = np.array([(0, 3, 5), (3, 1, 4), (5, 4, 2), (3, 4, 5)])
"""A P2 triangle (vertices 0-2, midsides 3 = 01, 4 = 12, 5 = 02) as four flat ones."""


def pad_cells(facets: np.ndarray, dim: int) -> tuple[np.ndarray, str]:
    """(pyvista cell array, "faces" or "lines") of the contact facets (k, 6) (3D) or (k, 3) (2D:
    vertex, vertex, midside), in the candidates' numbering."""
    if dim == 3:
        tri = facets[:, SPLIT].reshape(-1, 3)
        return np.column_stack([np.full(len(tri), 3), tri]).ravel(), "faces"
    seg = np.concatenate([facets[:, [0, 2]], facets[:, [2, 1]]])
    return np.column_stack([np.full(len(seg), 2), seg]).ravel(), "lines"


def body_outline(model, pad_region: str):
    """The undeformed body's boundary but the pad (`pad_region`): triangles (3D) or edges (2D), as
    pyvista PolyData."""
    import pyvista as pv
    mesh = model.mesh
    b = mesh.facets[:, np.setdiff1d(mesh.boundary_facets(), model.region_facets(pad_region))].T
    cells = np.column_stack([np.full(len(b), b.shape[1]), b]).ravel()
    points = pad3(mesh.p.T)
    return pv.PolyData(points, faces=cells) if model.dim == 3 else pv.PolyData(points, lines=cells)


class PadPicture:
    """A pyvista plotter (off screen) showing the pad of a `fem.experiments.live.LiveModel`;
    `show(answer, colour)` moves and colours it."""

    def __init__(self, live, window=(760, 560)):
        import pyvista as pv
        self.dim = live.dim
        self.rest = pad3(live.pad_mm)
        cells, kind = pad_cells(live.facets, live.dim)
        self.pad = pv.PolyData(self.rest.copy(), **{kind: cells})
        for title in COLOURS.values():
            self.pad.point_data[title] = np.zeros(len(self.rest))
        self.plotter = pv.Plotter(off_screen=True, window_size=window)
        self.plotter.disable_anti_aliasing()
        self.plotter.ren_win.SetMultiSamples(0)          # 8x MSAA in software rendering costs 3x the time
        self.plotter.set_background("white")
        self.plotter.add_mesh(body_outline(live.model, CONTACT_REGION[live.dim]), color="lightgrey",
                              line_width=1, show_scalar_bar=False)
        self.colour = None
        self.actor = None
        self.approach = np.asarray(live.prepared.approach, float)
        self.plotter.view_vector(-self.approach + np.array([0.6, 0.0, -0.6]) * (self.dim == 3)
                                 + np.array([0.0, 0.0, 1.0]) * (self.dim == 2), viewup=(0, 0, 1) if self.dim == 3
                                 else (0, 1, 0))

    def show(self, answer, colour: str) -> None:
        """Move the pad by answer's deflection (mm, along its approach, true scale) and colour it
        by the surface column `colour` (a key of COLOURS)."""
        self.pad.points = self.rest + np.outer(answer.surface["deflection_mm"], answer.approach)
        for column, title in COLOURS.items():
            self.pad.point_data[title] = np.asarray(answer.surface[column], float)
        values = self.pad.point_data[COLOURS[colour]]
        lo, hi = float(values.min()), float(values.max())
        hi = hi if hi > lo else lo + 1e-12
        if colour != self.colour:
            if self.actor is not None:
                self.plotter.remove_actor(self.actor)     # and its scalar bar
            self.actor = self.plotter.add_mesh(self.pad, scalars=COLOURS[colour], cmap="viridis", clim=(lo, hi),
                                               line_width=4, scalar_bar_args={"title": COLOURS[colour],
                                                                              "color": "black", "fmt": "%.2g",
                                                                              "n_labels": 4, "position_x": 0.15,
                                                                              "width": 0.7})
            self.colour = colour
        self.pad.set_active_scalars(COLOURS[colour])
        self.actor.mapper.scalar_range = (lo, hi)

    def pick(self, x_px: float, y_px: float) -> np.ndarray | None:
        """The pad point (3,) mm (as drawn, deformed) under a pixel of the picture (origin at its
        bottom left), or None when the pixel shows no pad. In 2D, where the pad is a line, the
        point of the section's plane under the pixel."""
        import vtk
        renderer = self.plotter.renderer
        if self.dim == 2:
            renderer.SetDisplayPoint(float(x_px), float(y_px), 0.0)
            renderer.DisplayToWorld()
            world = np.asarray(renderer.GetWorldPoint(), float)
            return world[:3] / world[3]
        picker = vtk.vtkCellPicker()
        picker.SetTolerance(0.002)
        picker.PickFromListOn()
        picker.AddPickList(self.actor)
        if not picker.Pick(float(x_px), float(y_px), 0.0, renderer):
            return None
        return np.asarray(picker.GetPickPosition(), float)

