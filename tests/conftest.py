import os
import subprocess
import sys
from pathlib import Path

# The suite runs dozens of kinds of models: one copy of the kernels with every feature compiled
# in serves them all (each kind would otherwise compile its own copy, about a minute each on 2
# cores; kernels/features.py).  tests/test_kernel_features.py turns the copies back on.  Set
# before dttmm is imported; the CLI's subprocesses inherit it.
os.environ.setdefault("DTTMM_SPECIALIZE", "0")

sys.path.insert(0, str(Path(__file__).parent))


def pytest_configure(config):
    """With pytest-xdist's workers (-n 2, -n auto), first compile the kernels most tests share,
    once, in two processes side by side (tests/warm_kernels.py): each worker would otherwise
    compile them too, at the same time.  A part that fails leaves its kernels to the tests (which
    then report the failure themselves)."""
    if hasattr(config, "workerinput") or not isinstance(
            getattr(config.option, "numprocesses", None), int) or config.option.numprocesses < 2:
        return
    print("tests/warm_kernels.py: compiling the kernels most tests share, in two processes "
          "(minutes on a fresh clone, seconds with numba's cache warm)", file=sys.stderr,
          flush=True)
    script = str(Path(__file__).with_name("warm_kernels.py"))
    parts = [subprocess.Popen([sys.executable, script, part], stdout=subprocess.DEVNULL,
                              stderr=subprocess.DEVNULL) for part in ("general", "others")]
    for part in parts:
        part.wait()
