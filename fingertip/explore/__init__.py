"""The live explorer in the browser (`pipeline.py explore`): a trame app over a model folder's stored
response model (`fem.experiments.live.LiveModel`). `fingertip.explore.picture` draws the pad in a
pyvista plotter rendered on the server, `fingertip.explore.app` lays out the controls and views and
answers every change. Needs the optional extra `explore` (trame, trame-vtk, trame-vuetify)."""
