"""What the mechanoreceptors feel and how afferents fire: receptor grids and their sampling,
recorded rates and the linear receptor model fitted to them, the 2D probe experiments, the
lumped receptor dynamics, and the spiking afferents (the published TouchSim transduction).

Modules: grid (receptor_grid, ReceptorSampler), neural (NeuralData and its CSV), analysis
(analyze), probes (Probe2D), dynamics (LumpedReceptor), transduction (spike_trains), afferents
(populations over a 3D pad).
"""
from fingertip.lazy import lazy_exports

_EXPORTS = {
    "receptor_grid": "fem.receptors.grid", "ReceptorGrid": "fem.receptors.grid",
    "ReceptorSampler": "fem.receptors.grid", "DEFAULT_DEPTHS_MM": "fem.receptors.grid",
    "NeuralData": "fem.receptors.neural", "read_neural_csv": "fem.receptors.neural",
    "write_neural_csv": "fem.receptors.neural", "analyze": "fem.receptors.analysis",
    "Probe2D": "fem.receptors.probes", "LumpedReceptor": "fem.receptors.dynamics",
    "spike_trains": "fem.receptors.transduction", "CLASSES": "fem.receptors.transduction",
    "Population": "fem.receptors.afferents", "PopulationResponse": "fem.receptors.afferents"
}
"""Public name -> the module that defines it (imported at first use: `fingertip.lazy`)."""
__all__ = sorted(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
