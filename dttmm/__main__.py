"""python -m dttmm: the command line (dttmm/interfaces/cli.py)."""
import sys

from .interfaces.cli import main

sys.exit(main())
