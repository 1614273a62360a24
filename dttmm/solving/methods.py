"""simulate's table of methods (issue 31), in the style of scipy.integrate's: each
time-stepping scheme by name, with what it supports and how it runs, read by simulate, its
drivers (drivers.py), the prepared runs (run_plan.py) and the CLI; and the sweep's two forms.
A new scheme is one entry here and its loop variant (kernels/) or integrator; the element kinds
say which schemes they run in (elements/kinds.py, Kind.schemes).
"""
from dataclasses import dataclass

from ..elements import kinds


@dataclass(frozen=True)
class Scheme:
    """One time-stepping scheme of simulate(scheme=name)."""
    name: str
    summary: str
    adaptive: bool              # steps chosen by its local error estimate (rtol=)
    richardson: bool            # extrapolated from runs at dt and dt / 2 (richardson=True)
    damping: bool               # takes rho_inf < 1 (numerical damping)
    newton_iterations: object   # its default extra iterations; None: the model's
    #                             (run_options.default_newton_iterations)
    stop_unconverged: bool      # a step whose iterations do not converge stops the run
    loads_at_midpoints: bool    # its loads are evaluated at the steps' midpoints, not ends
    loop: str                   # its loop variant family (run_plan.LOOP_BUILDERS)
    records: tuple = ()         # what it records beyond the state
    #                             (kernels/stepping/loop.py::Record)


SCHEMES = {scheme.name: scheme for scheme in (
    Scheme("newmark", "generalized-alpha (Chung and Hulbert 1993; rho_inf = 1: the "
           "trapezoidal rule), second order; every element, joint and topology, closed loops",
           adaptive=True, richardson=True, damping=True, newton_iterations=None,
           stop_unconverged=False, loads_at_midpoints=False, loop="newmark"),
    Scheme("energy_momentum", "conserves the total energy and the angular momentum to "
           "newton_tol; rigid chains with ball and fixed hinges on a fixed ground, and free "
           "chains (free joints; their linear momentum too)",
           adaptive=False, richardson=False, damping=False, newton_iterations=20,
           stop_unconverged=True, loads_at_midpoints=True, loop="energy_momentum",
           records=("v_c",)),
    Scheme("paper", "the paper's scheme (every station point with its own position "
           "history), for comparison only", adaptive=False, richardson=False, damping=True,
           newton_iterations=None, stop_unconverged=False, loads_at_midpoints=False,
           loop="general", records=("v_st", "v_c")),
    Scheme("dop853", "Dormand and Prince's explicit Runge-Kutta of order 8 (embedded error "
           "estimate of orders 5 and 3, dense output of order 7) on the rotation group, "
           "compiled with the acceleration sweep; steps chosen by rtol and atol; chains and "
           "trees of rigid bodies and beams on ball joints, a fixed ground, gravity",
           adaptive=True, richardson=False, damping=False, newton_iterations=0,
           stop_unconverged=False, loads_at_midpoints=False, loop="runge_kutta"),
)}

# the sweep's forms (simulate(method=...)): how each step's transfer equations are solved
SWEEPS = {
    "riccati": "the Riccati transfer (default): stable for long and stiff chains, trees, joints "
               "and loops",
    "direct": "the transfer matrices multiplied out, as the paper does: chains only; loses "
              "accuracy on long or stiff chains",
}

assert tuple(SCHEMES) == kinds.SCHEMES, "the element kinds' schemes are the table's"


def scheme_named(name):
    """The table's entry of a scheme, or a ValueError naming the ones there are."""
    try:
        return SCHEMES[name]
    except (KeyError, TypeError):
        raise ValueError(f"simulate: scheme must be one of {tuple(SCHEMES)}, got "
                         f"{name!r}") from None
