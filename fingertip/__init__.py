"""The fingertip toolkit's own namespace: the infrastructure every stage shares (errors,
declared parameters, package faces, progress, atomic output, tables, distribution), the jobs
behind the commands (`fingertip.jobs`) and the command line (`fingertip.cli`, the console
script `fingertip`). The science is in `fem` and `reconstruct`.
"""
