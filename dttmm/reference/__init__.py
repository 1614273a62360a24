"""Independent reference solver (global Newton-Euler equations), for checking DT-TMM results."""
from .newton_euler import simulate_reference

__all__ = ["simulate_reference"]
