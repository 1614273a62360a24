import os
import sys
from pathlib import Path

# The suite runs dozens of kinds of models: one copy of the kernels with every feature compiled
# in serves them all (each kind would otherwise compile its own copy, about a minute each on 2
# cores; kernels/features.py).  tests/test_kernel_features.py turns the copies back on.  Set
# before dttmm is imported; the CLI's subprocesses inherit it.
os.environ.setdefault("DTTMM_SPECIALIZE", "0")

sys.path.insert(0, str(Path(__file__).parent))
