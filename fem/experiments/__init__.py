"""The indentation experiments of a scene on a model folder: the scene schema (TOML or flags),
time courses, stored response models, and the scene runner every front end calls.

Modules: scene (Scene, load_scene), traces (time courses), response (ResponseStore), runner
(run_scene, run_experiments, prepare_responses).
"""
from fingertip.lazy import lazy_exports

_EXPORTS = {
    "Scene": "fem.experiments.scene", "Experiment": "fem.experiments.scene",
    "Receptors": "fem.experiments.scene", "load_scene": "fem.experiments.scene",
    "parse_values": "fem.experiments.values", "fractions": "fem.experiments.traces",
    "ResponseStore": "fem.experiments.response", "run_scene": "fem.experiments.runner",
    "run_experiments": "fem.experiments.runner", "prepare_responses": "fem.experiments.runner",
    "SceneRun": "fem.experiments.runner"
}
"""Public name -> the module that defines it (imported at first use: `fingertip.lazy`)."""
__all__ = sorted(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
