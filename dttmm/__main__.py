"""python -m dttmm: the command line (dttmm/cli.py)."""
import sys

from .cli import main

sys.exit(main())
