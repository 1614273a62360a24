"""The interfaces (docs/README.md, "Layout"): scene files (scene.py, the shipped scenes in
scenes/), the command line (cli.py: dttmm run | info | example | compile), ahead-of-time
compiling (precompile.py), a model in words (describe.py: Model.describe, set when dttmm is
imported), and parameter sweeps (parameter_sweep.py).  The top layer: it imports everything
below it, and nothing imports it but dttmm/__init__.py and dttmm/__main__.py."""
