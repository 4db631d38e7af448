"""pytetwild in a process of its own, made reproducible: the same inputs give the same tets, bit
for bit, on every run and every machine of one platform.

fTetWild seeds the order in which it inserts the surface triangles from `std::random_device`
(hardware entropy), so two runs on the same inputs gave different meshes (the monkey preset at
1 mm: 13,835-14,870 tets over four runs, on one thread or two). The worker process runs with a
small library preloaded (`LD_PRELOAD`) whose `std::random_device::_M_getval` returns a fixed
sequence, and on one thread: the monkey preset at 1 mm then gave 15,534 tets with the same bytes
in every run (docs/model-and-mesh.md). The library is built once, from the C source below, with
the machine's C compiler into the cache folder; without a compiler (or off Linux) meshes stay
unreproducible and a warning says so.

The worker is also the only process that imports pytetwild, whose C++ (geogram) replaces the
process's SIGINT handler on import: the caller keeps Python's, a terminal's Ctrl-C reaches the
caller only (the worker has a session of its own), and the caller then ends the worker.

    points, tets = run_tetwild({"vertices": v, "faces": f, ...})     # pytetwild.tetrahedralize's keywords
"""
from __future__ import annotations

import hashlib
import json
import logging
import os
import shlex
import subprocess
import sys
import sysconfig
import tempfile
from functools import lru_cache
from pathlib import Path

import numpy as np

from fingertip.progress import cache_root

logger = logging.getLogger(__name__)

FIXED_SEED_SOURCE = """\
/* std::random_device::_M_getval with a fixed sequence (a linear congruential generator): the
   "hardware" seeds of a program that preloads this become the same on every run. */
static unsigned int state = 0x2545F491u;
int fingertip_fixed_random_device = 1;
unsigned int _ZNSt13random_device9_M_getvalEv(void *self) {
    (void)self;
    state = state * 1664525u + 1013904223u;
    return state;
}
"""
THREADS = 1
"""pytetwild's threads: one, so that the mesh does not depend on the machine's core count."""


@lru_cache(maxsize=1)
def fixed_seed_library() -> Path | None:
    """The preloadable library of FIXED_SEED_SOURCE, built once into the cache folder
    (<cache>/native/), or None where it cannot be (not Linux, no C compiler): then logged."""
    if not sys.platform.startswith("linux"):
        logger.warning("meshes are not reproducible run to run on this platform (pytetwild seeds itself "
                       "from hardware entropy; the fixed seed is preloaded on Linux only)")
        return None
    digest = hashlib.sha256(FIXED_SEED_SOURCE.encode()).hexdigest()[:12]
    folder = cache_root() / "native"
    target = folder / f"fixed_random_device-{digest}.so"
    if target.is_file():
        return target
    compiler = shlex.split(sysconfig.get_config_var("CC") or "cc")
    try:
        folder.mkdir(parents=True, exist_ok=True)
        with tempfile.TemporaryDirectory(dir=folder) as tmp:
            src, out = Path(tmp) / "fixed.c", Path(tmp) / "fixed.so"
            src.write_text(FIXED_SEED_SOURCE)
            subprocess.run([*compiler, "-O2", "-shared", "-fPIC", "-o", str(out), str(src)], check=True,
                           capture_output=True, timeout=120)
            os.replace(out, target)
    except (OSError, subprocess.SubprocessError) as exc:
        logger.warning(f"meshes are not reproducible run to run: the fixed seed for pytetwild could not be "
                       f"built with {compiler[0]} ({' '.join(str(exc).split())[:200]}); install a C compiler")
        return None
    return target


def run_tetwild(kwargs: dict) -> tuple[np.ndarray, np.ndarray]:
    """pytetwild.tetrahedralize(**kwargs) in a worker process (THREADS threads, the fixed seed
    preloaded where it can be) -> (points (P, 3), tets (T, 4)). kwargs: arrays and plain values;
    its num_threads is replaced by THREADS."""
    arrays = {k: v for k, v in kwargs.items() if isinstance(v, np.ndarray)}
    plain = {k: v for k, v in kwargs.items() if k not in arrays} | {"num_threads": THREADS}
    env = dict(os.environ, OMP_NUM_THREADS=str(THREADS))
    library = fixed_seed_library()
    if library is not None:
        env["LD_PRELOAD"] = " ".join(filter(None, [str(library), env.get("LD_PRELOAD", "")]))
    with tempfile.TemporaryDirectory(prefix="tetwild-") as tmp:
        np.savez(Path(tmp) / "in.npz", **arrays)
        (Path(tmp) / "in.json").write_text(json.dumps(plain))
        proc = subprocess.Popen([sys.executable, "-m", "fem.geometry.tetwild", tmp], env=env, start_new_session=True,
                                stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
        try:
            _, err = proc.communicate()
        except BaseException:                          # Ctrl-C, SIGTERM: the worker ends with the caller
            proc.kill()
            proc.wait()
            raise
        if proc.returncode != 0:
            raise RuntimeError(f"pytetwild failed (exit {proc.returncode}): {' '.join(err.decode()[-400:].split())}")
        with np.load(Path(tmp) / "out.npz") as out:
            return out["points"], out["tets"]


def _work(folder: Path) -> None:
    """The worker: the inputs of `run_tetwild` from folder, pytetwild's output into folder/out.npz."""
    import pytetwild  # 0.17 s of import, in the worker only

    with np.load(folder / "in.npz") as arrays:
        kwargs = {**{k: arrays[k] for k in arrays.files}, **json.loads((folder / "in.json").read_text())}
    points, tets = pytetwild.tetrahedralize(**kwargs)
    np.savez(folder / "out.npz", points=points, tets=tets)


if __name__ == "__main__":
    _work(Path(sys.argv[1]))
