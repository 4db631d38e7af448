"""The explorer's web app (trame, Vue 3 and Vuetify): controls on the left (indentor, orientation,
position, depth or force, receptor depth and measure, colour, afferent class), the pad on the right
(rendered on the server, `fingertip.explore.picture`; drag to turn it), the numbers, the receptor
map and the surface profile below. Every change of the stimulus is one
`fem.experiments.live.LiveModel.answer`; a change of the receptor depth, measure or colour only
redraws. "fire afferents" (3D) runs `LiveModel.fire` for the current stimulus on its own thread
(seconds: it factorises) and shows the afferents' rate map and numbers while the stimulus stays.

    serve(LiveModel("out/monkey"), port=8080, scenes_dir=Path("."))   # blocks until Ctrl+C

The page's elements the tests and the latency benchmark read carry ids: `value` (the depth or
force field), `force`, `force-exact` (repr of the force), `answers` (how many answers so far),
`answered-at` (the server's time.time() once the picture of the latest answer was pushed), `drawn`
(the answer whose plots are shown), `fire` (the button), `afferents` (the firing's numbers),
`spikes` (the firing's total spike count).
"""
from __future__ import annotations

import asyncio
import base64
import io
import sys
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np

from fem.contact.facets import PEAK_PRESSURE_RADIUS_MM
from fem.experiments.live import AFFERENT_TRACE
from fem.plots import explorer_profile_figure, plain_numbers, rate_map_figure, receptor_map_figure
from fem.receptors.transduction import CLASSES
from fingertip.errors import InputError
from fingertip.explore.picture import COLOURS, PadPicture

INDENTORS = ["C1", "C2", "C3", "C4", "C5", "C6", "C7", "C8", "R1", "R2", "bar:0.5", "bar:1.5", "bar:3",
             "grating:1:1,2,3", "step:0", "step:3", "wedge", "cone", "punch", "plate", "sphere:2", "sphere:5",
             "ellipsoid:2,3,2", "two-point:2"]
"""Indentor codes offered in the list (any code of fem.contact.indentors can be typed)."""
PROFILE_BAND_MM = 0.5
"""3D: the surface profile shows the pad nodes within this distance of the indentor's position
across the finger axis (z)."""


def png_url(fig, dpi: int = 80) -> str:
    """A matplotlib Figure as a data: URL of its PNG."""
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=dpi, pil_kwargs={"compress_level": 1})     # speed over size
    return "data:image/png;base64," + base64.b64encode(buf.getvalue()).decode()


class Plots:
    """The receptor map and the surface profile, drawn once per receptor depth and measure and
    then only given new values (a redraw, not a new figure: about 2x faster)."""

    def __init__(self, live):
        self.live, self.map_key, self.map_fig = live, None, None
        self.profile_fig = explorer_profile_figure([0.0], [0.0], [0.0], "x, mm")
        self.lines = [ax.lines[0] for ax in self.profile_fig.axes]
        plain_numbers(self.profile_fig)

    def receptor_map(self, answer, depth_mm: float, measure: str) -> str:
        """PNG data URL of `measure` at the receptor points `depth_mm` deep."""
        r = answer.receptors
        at = np.isclose(r["depth_mm"], depth_mm)
        values = r[measure][at]
        if self.map_key != (depth_mm, measure):
            across = r["z_mm"] if self.live.dim == 3 else r["y_mm"]
            self.map_fig = receptor_map_figure(r["x_mm"][at], across[at], values, measure, depth_mm, self.live.dim)
            plain_numbers(self.map_fig)
            self.map_key = (depth_mm, measure)
        art = self.map_fig.axes[0].collections[0]
        art.set_array(values)
        art.set_clim(float(values.min()), float(values.max()) if values.max() > values.min() else values.min() + 1e-12)
        return png_url(self.map_fig)

    def profile(self, answer) -> str:
        """PNG data URL of the deflection and pressure along x through the indentor (`profile_of`)."""
        x, deflection, pressure = profile_of(self.live, answer)
        for line, ax, y in zip(self.lines, self.profile_fig.axes, (-deflection, pressure)):
            line.set_data(x, y)
            ax.relim()
            ax.autoscale_view()
        return png_url(self.profile_fig)


def experiment_of(live, s) -> dict:
    """The [[experiment]] table of the page's state `s` (values as the page holds them: text or
    numbers); InputError for a value that is not a number."""
    def num(name):
        try:
            value = float(s[name])
        except (TypeError, ValueError):
            raise InputError(f"{name.replace('_', ' ')}: {s[name]!r} is not a number") from None
        if not np.isfinite(value):
            raise InputError(f"{name.replace('_', ' ')}: give a finite number")
        return value
    e = {"indentor": str(s["indentor"]).strip()}
    if live.dim == 3:
        e["orientation"] = num("orientation_deg")
        e["position_mm"] = [num("x_mm"), num("z_mm")]
    else:
        e["position_mm"] = [num("x_mm"), 0.0]
    if s["control"] == "force":
        e["force_N"] = num("value")
    else:
        e["depth_mm"] = [num("value")]
    return e


def profile_of(live, answer) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(x (n,) mm, deflection (n,) mm, pressure (n,) MPa) of the pad nodes along x through the
    indentor (3D: within PROFILE_BAND_MM of its z), in order of x."""
    x, z = answer.surface["x_mm"], answer.surface["z_mm"]
    keep = np.ones(len(x), bool)
    if live.dim == 3:
        keep = np.abs(z - answer.experiment["position_mm"][1]) <= PROFILE_BAND_MM
    order = np.argsort(x[keep], kind="stable")
    return (x[keep][order], answer.surface["deflection_mm"][keep][order],
            answer.surface["pressure_MPa"][keep][order])


def number_texts(live, a) -> dict:
    """The page's number lines of an answer, with units (2D: per mm of length, widths)."""
    per = " per mm" if live.dim == 2 else ""
    area = f"{a.contact_area_mm2:.4g} mm" if live.dim == 2 else f"{a.contact_area_mm2:.4g} mm²"     # 2D: a width
    return {"force_text": f"{a.force_N:.6g} N{per}", "force_exact": repr(a.force_N),
            "depth_text": f"{a.depth_mm:.4g} mm", "area_text": area,
            "pressure_text": f"{a.peak_pressure_MPa:.4g} MPa; at a node {a.max_pressure_MPa:.4g} MPa", "answer_ms": f"{1e3 * a.seconds:.0f} ms"}


def firing_text(f) -> str:
    """The page's line on a `fem.experiments.live.Firing`."""
    rate = np.asarray(f.afferents["rate_hz"])
    t = AFFERENT_TRACE
    course = f"ramp {t['ramp_s']:g} s, hold {t['hold_s']:g} s, release {t['release_s']:g} s"
    if not f.firing.any():
        return f"{len(rate)} {f.afferent_class} afferents, none fires ({course}; {f.seconds:.1f} s)"
    return (f"{len(rate)} {f.afferent_class} afferents, {int(f.firing.sum())} fire: mean rate over the course "
            f"{rate[f.firing].mean():.3g} Hz (those firing), highest {rate.max():.3g} Hz ({course}; {f.seconds:.1f} s)")


def initial_state(live) -> dict:
    """The page's state before the first answer: C5 across the middle of the pad, 0.5 mm deep."""
    pad = live.pad_mm
    middle_z = 0.5 * (pad[:, 2].min() + pad[:, 2].max()) if live.dim == 3 else 0.0
    return {"indentor": "C5", "orientation_deg": 90.0 if live.dim == 3 else 0.0, "x_mm": 0.0,
            "z_mm": round(float(middle_z), 3), "control": "depth", "value": 0.5,
            "receptor_depth": live.depths_mm[len(live.depths_mm) // 2], "measure": live.measures[0],
            "colour": "pressure_MPa", "click_places": True, "error": "", "warning": "", "answers": 0, "drawn": 0,
            "answered_at": 0.0, "scene_name": "explorer_scene.toml", "saved": "", "map_src": "", "profile_src": "",
            "afferent_class": "SA1", "firing": False, "afferents_text": "", "spikes": "", "rate_map_src": "",
            "save_afferents": False,
            **dict.fromkeys(("force_text", "force_exact", "depth_text", "area_text", "pressure_text", "answer_ms"),
                            "")}


class Explorer:
    """The trame server of the explorer over `live` (a LiveModel), saving scenes into scenes_dir:
    its state, its handlers (one per kind of change) and its page."""

    def __init__(self, live, scenes_dir: Path):
        from trame.app import get_server
        self.live, self.scenes_dir = live, Path(scenes_dir)
        self.server = get_server("fingertip-explorer", client_type="vue3")
        self.state, self.ctrl = self.server.state, self.server.controller
        self.picture, self.plots = PadPicture(live), Plots(live)
        self.plotting = ThreadPoolExecutor(1, thread_name_prefix="plots")    # one figure at a time
        self.firing = ThreadPoolExecutor(1, thread_name_prefix="afferents")   # one firing at a time
        self.held = None                                                     # the latest Answer
        self.state.update(initial_state(live))
        self.state.change("indentor", "orientation_deg", "x_mm", "z_mm", "control", "value")(self.answer)
        self.state.change("receptor_depth", "measure")(self.redraw)
        self.state.change("colour")(self.recolour)
        page(self)
        self.answer()
        self.picture.plotter.reset_camera()

    def answer(self, **_):
        """A new stimulus: its answer's numbers and picture now, its plots on the plotting thread."""
        from trame.app import asynchronous
        state = self.state
        try:
            a = self.live.answer(experiment_of(self.live, state))
        except InputError as exc:
            state.error = str(exc)
            return
        self.held = a
        state.error, state.warning = "", " ".join(a.warnings)
        if state.rate_map_src or state.afferents_text:     # a firing belongs to the stimulus before
            state.rate_map_src, state.afferents_text, state.spikes = "", "", ""
        state.update(number_texts(self.live, a))
        self.picture.show(a, state.colour)
        self.ctrl.view_update()              # renders and pushes the picture
        state.answers += 1
        state.answered_at = time.time()
        asynchronous.create_task(self.draw_plots(state.answers))

    async def draw_plots(self, answers: int):
        """The receptor map and profile of answer `answers`, drawn on the plotting thread while the
        server sends that answer's numbers and picture."""
        a, depth, measure = self.held, float(self.state.receptor_depth), self.state.measure
        profile, receptor_map = await asyncio.get_running_loop().run_in_executor(
            self.plotting, lambda: (self.plots.profile(a), self.plots.receptor_map(a, depth, measure)))
        if answers != self.state.answers:    # a newer answer draws its own
            return
        with self.state:
            self.state.profile_src, self.state.map_src, self.state.drawn = profile, receptor_map, answers

    def redraw(self, **_):
        """Another receptor depth or measure: the plots again."""
        from trame.app import asynchronous
        if self.held is not None:
            asynchronous.create_task(self.draw_plots(self.state.answers))

    def recolour(self, **_):
        """Another colour of the pad."""
        if self.held is not None:
            self.picture.show(self.held, self.state.colour)
            self.ctrl.view_update()

    def fire(self):
        """The afferents of the chosen class under AFFERENT_TRACE to the current stimulus, fired on
        the afferent thread; shown if the stimulus has not changed meanwhile."""
        from trame.app import asynchronous
        state = self.state
        try:
            experiment = experiment_of(self.live, state)
            self.live.scene(experiment, state.afferent_class)
        except InputError as exc:
            state.afferents_text = str(exc)
            return
        state.firing, state.rate_map_src, state.spikes = True, "", ""
        state.afferents_text = f"firing the {state.afferent_class} afferents (the model is factorised: seconds)"
        asynchronous.create_task(self.show_firing(experiment, state.afferent_class, state.answers))

    async def show_firing(self, experiment: dict, afferent_class: str, answers: int):
        """Fire on the afferent thread, then show the rate map and numbers of answer `answers`."""
        def work():
            f = self.live.fire(experiment, afferent_class)
            return f, png_url(rate_map_figure(f.response, width_in=4.4))
        try:
            f, url = await asyncio.get_running_loop().run_in_executor(self.firing, work)
        except InputError as exc:
            with self.state:
                self.state.firing, self.state.afferents_text = False, str(exc)
            return
        with self.state:
            self.state.firing = False
            if answers != self.state.answers:
                self.state.afferents_text = "the stimulus changed while the afferents fired: fire again"
                return
            self.state.afferents_text, self.state.rate_map_src = firing_text(f), url
            self.state.spikes = str(int(np.sum(f.afferents["spikes"])))

    def place(self, event):
        """A click on the picture: the indentor moves to the pad point under it."""
        if not self.state.click_places or not isinstance(event, dict) or "position" not in event:
            return
        point = self.picture.pick(event["position"]["x"], event["position"]["y"])
        if point is not None:
            self.state.update({"x_mm": round(float(point[0]), 2),
                               **({"z_mm": round(float(point[2]), 2)} if self.live.dim == 3 else {})})

    def save_scene(self):
        """The current stimulus as a scene file in the scenes folder, under the name typed."""
        name = str(self.state.scene_name).strip()
        if not name or Path(name).name != name or not name.endswith(".toml"):
            self.state.saved = f"give a file name ending in .toml (no folder): it is saved in {self.scenes_dir}"
            return
        try:
            text = self.live.scene_toml(experiment_of(self.live, self.state), comment="saved by pipeline.py explore",
                                        afferent_class=self.state.afferent_class if self.state.save_afferents else None)
        except InputError as exc:
            self.state.saved = str(exc)
            return
        (self.scenes_dir / name).write_text(text)
        self.state.saved = f"saved {self.scenes_dir / name}"


def page(ex: Explorer) -> None:
    """The page: the controls in the drawer, the views in the content."""
    from trame.ui.vuetify3 import SinglePageWithDrawerLayout
    from trame.widgets import html
    from trame.widgets import vuetify3 as v3
    live, pad, compact = ex.live, ex.live.pad_mm, {"density": "compact"}
    with SinglePageWithDrawerLayout(ex.server) as layout:
        layout.title.set_text(f"Fingertip explorer: {live.model_dir.name}")
        with layout.drawer as drawer, v3.VContainer(classes="pa-3"):
            drawer.width = 330
            v3.VCombobox(label="indentor", v_model=("indentor",), items=("indentors", INDENTORS), id="indentor",
                         **compact)
            sliders = [("orientation, deg", "orientation_deg", 0.0, 180.0, 5)] if live.dim == 3 else []
            sliders += [("x, mm", "x_mm", pad[:, 0].min(), pad[:, 0].max(), 0.05)]
            sliders += [("z, mm", "z_mm", pad[:, 2].min(), pad[:, 2].max(), 0.05)] if live.dim == 3 else []
            for label, key, lo, hi, step in sliders:
                v3.VSlider(label=label, v_model=(key,), min=round(float(lo), 2), max=round(float(hi), 2), step=step,
                           thumb_label=True, **compact)
            with v3.VBtnToggle(v_model=("control",), mandatory=True, classes="mb-2", **compact):
                v3.VBtn("depth", value="depth")
                v3.VBtn("force", value="force")
            per = " per mm" if live.dim == 2 else ""
            v3.VTextField(label=(f"control == 'force' ? 'force, N{per}' : 'depth, mm'",), v_model=("value",),
                          type="number", step=0.05, id="value", **compact)
            v3.VSwitch(label="a click on the pad places the indentor", v_model=("click_places",), color="primary",
                       hide_details=True, **compact)
            v3.VSelect(label="receptor depth, mm", v_model=("receptor_depth",), items=("depths", live.depths_mm),
                       **compact)
            v3.VSelect(label="receptor measure", v_model=("measure",), items=("measures", list(live.measures)),
                       **compact)
            v3.VSelect(label="colour the pad by", v_model=("colour",),
                       items=("colours", [{"title": t, "value": k} for k, t in COLOURS.items()]), **compact)
            if live.dim == 3:
                v3.VSelect(label="afferent class", v_model=("afferent_class",), items=("classes", list(CLASSES)),
                           id="afferent-class", **compact)
                v3.VBtn("fire afferents", click=ex.fire, id="fire", block=True, loading=("firing",),
                        disabled=("firing",), classes="mb-1")
                html.Div("{{ afferents_text }}", id="afferents", classes="text-caption mb-2")
                v3.VSwitch(label="save with the afferents (ramp and hold)", v_model=("save_afferents",),
                           id="save-afferents", color="primary", hide_details=True, **compact)
            v3.VTextField(label=f"save as scene in {ex.scenes_dir}", v_model=("scene_name",), id="scene-name",
                          **compact)
            v3.VBtn("save as scene", click=ex.save_scene, id="save", block=True)
            html.Div("{{ saved }}", id="saved", classes="text-caption mt-1")
        with layout.content, v3.VContainer(fluid=True, classes="pa-2"):
            views(ex)


def views(ex: Explorer) -> None:
    """The alerts, the pad's picture, the numbers, the receptor map and the profile; hidden
    counters for tests and benchmarks."""
    from trame.widgets import html
    from trame.widgets import vtk as vtk_widgets
    from trame.widgets import vuetify3 as v3
    v3.VAlert("{{ error }}", v_if="error", type="error", density="compact", id="error")
    v3.VAlert("{{ warning }}", v_if="warning", type="warning", density="compact", id="warning")
    with v3.VRow(dense=True):
        with v3.VCol(cols=7), html.Div(style="height: 560px; border: 1px solid #ddd", id="picture"):
            view = vtk_widgets.VtkRemoteView(ex.picture.plotter.ren_win, interactive_ratio=1, still_quality=85,
                                             picking_modes=("click_places ? ['click'] : []",),
                                             click=(ex.place, "[$event]"))
            ex.ctrl.view_update = view.update
        with v3.VCol(cols=5):
            area = "contact width" if ex.live.dim == 2 else "contact area"
            with html.Table(classes="text-body-2 mb-2"):
                for label, key, ident in (("force", "force_text", "force"), ("depth", "depth_text", "depth"),
                                          (area, "area_text", "area"), (f"peak pressure over {PEAK_PRESSURE_RADIUS_MM:g} mm", "pressure_text", "pressure"),
                                          ("answered in", "answer_ms", "answer-ms")):
                    with html.Tr():
                        html.Td(label, classes="pr-4")
                        html.Td(f"{{{{ {key} }}}}", id=ident)
            html.Img(src=("map_src",), style="width: 100%; max-width: 440px")
            html.Img(src=("profile_src",), style="width: 100%; max-width: 440px")
            html.Img(src=("rate_map_src",), v_if="rate_map_src", style="width: 100%; max-width: 440px")
    for key, ident in (("force_exact", "force-exact"), ("answers", "answers"), ("answered_at", "answered-at"),
                       ("drawn", "drawn"), ("spikes", "spikes")):
        html.Span(f"{{{{ {key} }}}}", id=ident, style="display: none")


def serve(live, port: int, scenes_dir: Path, open_browser: bool = False, ready=None) -> None:
    """Run the explorer on http://127.0.0.1:<port>/ until interrupted; ready(): called once the
    server listens."""
    server = Explorer(live, scenes_dir).server
    if ready is not None:
        server.controller.on_server_ready.add(lambda **_: ready())
    argv, sys.argv = sys.argv, sys.argv[:1]       # trame reads its own flags from sys.argv
    try:
        server.start(port=port, host="127.0.0.1", open_browser=open_browser, show_connection_info=False,
                     timeout=0)
    finally:
        sys.argv = argv
