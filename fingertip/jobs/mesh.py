"""The `mesh` job: a model folder (mesh.vtu + model.json) from a `fem.geometry.build.MeshSpec`;
returns the summary text the command line prints."""
from __future__ import annotations

import logging

from fem.geometry.build import MeshSpec, build_folder
from fingertip.progress import as_progress
from fingertip.staging import check_output_dir, claimed

logger = logging.getLogger(__name__)


def check_mesh(out, spec: MeshSpec) -> None:
    """Every refusal of `mesh_folder`, reading no file: the spec, then the output folder."""
    spec.check()
    check_output_dir(out)


def mesh_folder(out, spec: MeshSpec, force: bool = False, progress=True) -> str:
    """Build the model folder `out` of `spec` (a current 3D folder is kept unless force); mesh
    warnings are logged. Returns the summary text."""
    check_mesh(out, spec)
    with claimed(out):
        built = build_folder(out, spec, force=force, progress=as_progress(progress))
    for warning in built.warnings:
        logger.warning(warning)
    return built.summary
