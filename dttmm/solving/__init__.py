"""Solving (docs/README.md, "Layout"): a model's tables as the kernels take them
(run_tables.py), what a run is refused for (run_checks.py), its inputs at given times
(run_inputs.py), the consistent start (consistent_start.py), chunks, samples and Richardson
extrapolation (run_records.py), the options and the plan of a run (run_options.py,
run_plan.py, methods.py, threads.py), the drivers of its loops (drivers.py, adaptive.py), the
checks during and after it (energy_balance.py, resolution.py), and the faces over them:
simulate (solver.py), static_equilibrium (statics.py), forward_dynamics, linearize and ode
(dynamics.py, loop_dynamics.py).  It imports the results, the model, the kernels, the elements
and vectors.py below it; the Newton-Euler reference (dttmm/reference/) stands beside it, and
neither imports the other."""
