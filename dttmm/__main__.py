"""python -m dttmm: the command line (dttmm/cli.py)."""
import sys

from .interfaces.cli import main

sys.exit(main())
