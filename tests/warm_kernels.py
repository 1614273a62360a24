"""Compile the kernels most of the suite shares once, before pytest-xdist's workers start
(tests/conftest.py::pytest_configure), in two processes side by side.  Without it both workers
compile them at the same time: on a fresh clone with 2 workers, 226 of the suite's 745 s of
compilation were spent twice (the general loop's start and skeleton 88 s of it, the
Newton-Euler reference's right-hand side 20 s; measured from numba's compile events).  Each part
runs a few steps of small models and leaves the compiled kernels in numba's cache (with a warm
cache it takes a few seconds):

    python tests/warm_kernels.py general    the general loop's start (which the welded and
                                            energy-momentum loops use too), skeleton and sweeps,
                                            the welded and energy-momentum loops
    python tests/warm_kernels.py others     the fused ball-joint loops, the Runge-Kutta loops
                                            and the Newton-Euler reference
"""
import os
import sys

os.environ.setdefault("DTTMM_SPECIALIZE", "0")      # the suite's one copy (conftest.py)


def general():
    from dttmm import chains, simulate
    simulate(chains.arm(flexible=True), 2e-3, 1e-3)
    simulate(chains.stiff_cantilever(2), 2e-3, 1e-3)
    simulate(chains.rigid_chain(3), 2e-3, 1e-3, scheme="energy_momentum")


def others():
    from dttmm import chains, simulate
    from dttmm.reference.newton_euler import simulate_reference
    chain = chains.rigid_chain(3)
    simulate(chain, 2e-3, 1e-3)
    simulate(chains.three_pendulum(), 2e-3, 1e-3)
    simulate(chains.binary_tree(2), 2e-3, 1e-3)
    simulate(chain, 2e-3, scheme="dop853", rtol=1e-6)
    simulate(chains.binary_tree(2), 2e-3, scheme="dop853", rtol=1e-6)
    simulate_reference(chain, 2e-3)


if __name__ == "__main__":
    {"general": general, "others": others}[sys.argv[1]]()
