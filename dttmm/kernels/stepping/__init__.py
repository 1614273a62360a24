"""The time loops: the step skeleton (loop.py) and its variants, the general loop (step.py), the
fused ball-chain, ball-tree and welded-chain loops (ball_chain.py, tree.py, weld_chain.py), the
energy-momentum loop (em_step.py), and the high-order integrator over the fused loops' sweep
(runge_kutta.py)."""
