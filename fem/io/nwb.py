"""A traced experiment's afferents as a Neurodata Without Borders file (NWB 2, `pynwb`: the
optional extra `nwb`), beside its CSVs: what neurophysiology labs keep recordings in, so that
model and recording are compared in the same tools.

The file holds one unit per afferent (its spike times in s; columns afferent_class, model_index,
the surface site x_mm, y_mm, z_mm above it and depth_mm below it; obs_intervals the course) and,
as stimulus, the indentor's depth and the contact force at each sample time of the course. A
simulation has no recording session: session_start_time and file_create_date are 1970-01-01 UTC
and every object id is derived from the file's contents, so that the same run writes the same
bytes (`write_nwb`).

    write_nwb("run/ramp_hold/spikes.nwb", "ramp_hold", response, depth_mm, force_N)
    with pynwb.NWBHDF5IO("run/ramp_hold/spikes.nwb", "r") as io:
        units = io.read().units          # units["spike_times"][i], units["afferent_class"][i]
"""
from __future__ import annotations

import hashlib
import importlib.util
import uuid
from datetime import datetime, timezone

import numpy as np

from fingertip.errors import InputError

INSTALL = 'pip install -e ".[nwb]"'
"""How to get the writer's library."""
FIXED_TIME = datetime(1970, 1, 1, tzinfo=timezone.utc)
"""session_start_time and file_create_date of every file (a simulation has no session)."""


def installed() -> bool:
    """Whether pynwb can be imported (found, not imported: its import takes a second)."""
    return importlib.util.find_spec("pynwb") is not None


def check_available() -> None:
    """Raise InputError when pynwb is not installed (before any computation)."""
    if not installed():
        raise InputError(f"[afferents] nwb = true writes NWB files with pynwb, which is not installed: {INSTALL}")


def write_nwb(path, name: str, resp, depth_mm, force_N) -> None:
    """Write `path`: the afferents of the experiment `name` (a
    fem.receptors.afferents.PopulationResponse), with its depth_mm (k,) [mm] and force_N (k,) [N]
    at the response's k sample times as the stimulus."""
    from pynwb import NWBHDF5IO, NWBFile, TimeSeries

    pop, times = resp.population, np.asarray(resp.times_s, float)
    digest = hashlib.sha256()
    for part in (name.encode(), times.tobytes(), *(np.asarray(s, float).tobytes() for s in resp.spikes),
                 pop.site_mm.tobytes(), "".join(pop.afferent_class.astype(str)).encode()):
        digest.update(part)
    identifier = f"fingertip-{name}-{digest.hexdigest()[:32]}"
    f = NWBFile(session_description=f"fingertip-fem simulation: the afferents of experiment '{name}'",
                identifier=identifier, session_start_time=FIXED_TIME, file_create_date=[FIXED_TIME],
                source_script="fingertip-fem (pipeline.py indent)", source_script_file_name="pipeline.py")
    columns = {"afferent_class": "SA1, RA or PC (the published afferent model's classes)",
               "model_index": "row of the class's published parameter table",
               "x_mm": "x of the skin surface site above the afferent [mm]",
               "y_mm": "y of the skin surface site above the afferent [mm]",
               "z_mm": "z of the skin surface site above the afferent [mm]",
               "depth_mm": "depth of the afferent below the skin surface [mm]"}
    for col, text in columns.items():
        f.add_unit_column(name=col, description=text)
    span = [[float(times[0]), float(times[-1])]]
    for i in range(len(pop)):
        x, y, z = (float(v) for v in pop.site_mm[i])
        f.add_unit(spike_times=np.asarray(resp.spikes[i], float), obs_intervals=span,
                   afferent_class=str(pop.afferent_class[i]), model_index=int(pop.model_index[i]),
                   x_mm=x, y_mm=y, z_mm=z, depth_mm=float(pop.depth_mm[i]))
    f.add_stimulus(TimeSeries(name="indentation_depth", data=np.asarray(depth_mm, float), unit="meters",
                              conversion=1e-3, timestamps=times,
                              description="depth of the indentor beyond first touch (data in mm)"))
    f.add_stimulus(TimeSeries(name="contact_force", data=np.asarray(force_N, float), unit="newtons",
                              timestamps=times, description="total contact force on the indentor"))
    for k, child in enumerate(f.all_children()):     # object ids from the contents, not random
        child._AbstractContainer__object_id = str(uuid.uuid5(uuid.NAMESPACE_URL, f"{identifier}/{k}"))
    with NWBHDF5IO(str(path), "w") as io:
        io.write(f)
