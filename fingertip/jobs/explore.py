"""The `explore` job: check everything a live explorer needs before any work (the optional extra,
the model folder, the material, the port, the folders it writes), find or build the stored
response model (`fem.experiments.live.LiveModel`, with progress), then serve the web app
(`fingertip.explore.app`) until interrupted."""
from __future__ import annotations

import importlib.util
import socket
from pathlib import Path

from fem.io.modelfolder import check_folder_material, folder_info
from fingertip.errors import InputError
from fingertip.progress import as_progress
from fingertip.staging import check_output_dir, check_writable_folder

EXTRA = ("trame", "trame_vtk", "trame_vuetify")
"""The modules of the optional extra `explore`."""
INSTALL = "pip install -e '.[explore]'"


def check_explore(model_dir, material=None, nu=None, port: int = 8080, scenes_dir=".") -> Path:
    """InputError, before any work, for what would stop the explorer: the extra not installed, a
    folder that is not a model folder, a material that does not fit it, a port in use, a model
    folder whose response store cannot be written, a scenes folder that cannot be. Returns the
    scenes folder."""
    missing = [m for m in EXTRA if importlib.util.find_spec(m) is None]
    if missing:
        raise InputError(f"the explorer needs the optional extra 'explore' ({', '.join(missing)} missing): {INSTALL}")
    folder_info(model_dir)
    check_folder_material(model_dir, material, nu)
    for folder in (Path(model_dir), Path(model_dir) / "response"):
        check_writable_folder(folder, "the model folder" if folder.name != "response" else "the folder")
    scenes = check_output_dir(scenes_dir, "--scenes")
    if not 0 < port < 65536:
        raise InputError(f"--port {port}: give a port from 1 to 65535")
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as probe:
        try:
            probe.bind(("127.0.0.1", port))
        except OSError:
            raise InputError(f"--port {port}: the port is in use on 127.0.0.1; give another (--port {port + 1})") \
                from None
    return scenes


def explore(model_dir, material=None, nu=None, receptors: dict | None = None, port: int = 8080, scenes_dir=".",
            open_browser: bool = False, progress=True) -> None:
    """Serve the explorer of a model folder on http://127.0.0.1:<port>/ (prints the URL) until
    Ctrl+C; scenes are saved into scenes_dir (made when missing)."""
    scenes = check_explore(model_dir, material, nu, port, scenes_dir)
    from fem.experiments.live import LiveModel
    from fingertip.explore.app import serve
    live = LiveModel(model_dir, material, nu, receptors, progress=as_progress(progress))
    scenes.mkdir(parents=True, exist_ok=True)
    url = f"http://127.0.0.1:{port}/"
    serve(live, port, scenes, open_browser, ready=lambda: print(
        f"explorer of {model_dir} (response model {live.prepared.key[:12]}, {live.prepared.how}): {url}  "
        f"(Ctrl+C stops it)", flush=True))
