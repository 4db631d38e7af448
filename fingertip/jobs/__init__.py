"""The jobs behind the commands: each checks its inputs, runs the science (`fem`,
`reconstruct`), writes its output folder atomically and returns the summary text the command
line prints. One module per command family: reconstruct (and the `run` chain), render, mesh,
indent (and `prepare`), biomech, analyze, batch, reproduce; tasks (what runs on Dask workers).
"""
