"""The files the toolkit ships with its code: the synthetic turntable set (sample_images/), the
scenes of the thesis's experiments (scenes/), the afferent tables and synthetic measured data
(data/) and the examples (examples/). They are found through the installed package
(importlib.resources: `fingertip/bundled/`), so a wheel installed anywhere has them as a checkout
does; in a checkout `fingertip/bundled/<name>` links to the folder at the repository's root.

    shipped("sample_images")          # Path of the bundled turntable set
    shipped_scene("ramp_hold")        # Path of scenes/ramp_hold.toml (None for an unknown name)
"""
from __future__ import annotations

from importlib.resources import files
from pathlib import Path

from fingertip.errors import InputError

SHIPPED = ("sample_images", "scenes", "data", "examples")
"""The shipped folders."""


def shipped(name: str) -> Path:
    """The folder (or file, `data/x.json`) `name` of the shipped files, as a path on disk."""
    path = Path(str(files("fingertip") / "bundled" / name))
    if not path.exists():
        raise InputError(f"the shipped file {name} is missing from this install ({path}); reinstall fingertip-fem")
    return path


def scene_names() -> list[str]:
    """Names of the shipped scenes (their file stems)."""
    return sorted(p.stem for p in shipped("scenes").glob("*.toml"))


def shipped_scene(name: str) -> Path | None:
    """The shipped scene file of a bare name ("ramp_hold" or "ramp_hold.toml"), else None."""
    stem = name[:-5] if name.endswith(".toml") else name
    if "/" in stem or "\\" in stem or stem not in scene_names():
        return None
    return shipped("scenes") / f"{stem}.toml"
