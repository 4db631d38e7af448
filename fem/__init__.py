"""Finite-element stage: layered model, mesh, solver, contact, experiments, receptors,
biomechanics and the thesis, one subpackage per concept (docs/design.md draws how they stand on
each other):

    core         materials, discretisation, Model, linear algebra, fields, measures, neo-Hookean
    geometry     presets, layered fingertip, 3D and 2D meshes, model folders built from them
    io           model folder, run folder, VTU/PVD
    contact      indentors, compliance, the contact solver
    verify       closed forms, half-space block
    receptors    receptor grids, neural data, analysis, probes, dynamics, transduction, afferents
    experiments  scene, time courses, stored response models, the scene runner
    biomech      deflection experiments, layer study, material fits, line load
    thesis       the source thesis claim by claim
    plots        every figure (matplotlib Figure objects)

The public names of every subpackage are names of `fem` too (`from fem import Model, run_scene`),
imported at first use (`fingertip.lazy`), so `import fem` stays light.
"""
from fem import (
    biomech,
    contact,
    core,
    experiments,
    geometry,
    io,
    receptors,
    thesis,
    verify,
)
from fingertip.errors import InputError
from fingertip.lazy import lazy_exports

_FACES = (core, geometry, io, contact, verify, receptors, experiments, biomech, thesis)
_EXPORTS = {name: module for face in _FACES for name, module in face._EXPORTS.items()}
"""Every subpackage's public name -> its module."""
if len(_EXPORTS) != sum(len(face._EXPORTS) for face in _FACES):
    raise ImportError("two fem subpackages export the same name")
__all__ = ["InputError", *sorted(_EXPORTS)]
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
