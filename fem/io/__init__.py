"""File formats: the model folder (mesh.vtu + model.json) read as a held, factorised model, the run
folder of the indentation experiments (written and read), VTU/PVD output of solutions, and the
row files of stored response models.

Modules: modelfolder (read_model, held regions, factorise), runfolder (write_run, IndentRun), vtu
(write_solution, write_vtu), rows (quantise, write_rows, RowFile), nwb.
"""
from fingertip.lazy import lazy_exports

_EXPORTS = {
    "read_model": "fem.io.modelfolder", "folder_info": "fem.io.modelfolder",
    "held_regions": "fem.io.modelfolder", "factorise": "fem.io.modelfolder",
    "open_model": "fem.io.modelfolder", "CONTACT_REGION": "fem.io.modelfolder",
    "write_run": "fem.io.runfolder", "IndentRun": "fem.io.runfolder", "write_solution": "fem.io.vtu",
    "write_vtu": "fem.io.vtu"
}
"""Public name -> the module that defines it (imported at first use: `fingertip.lazy`)."""
__all__ = sorted(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
