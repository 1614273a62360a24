"""What is simulated (docs/README.md, "Layout"): the frozen Model (model.py), System and
build_chain (system.py), validated and frozen into a Model by freeze.py over the shortest
spanning tree (spanning_tree.py); the closing joints (closures.py), the end sections and output
points (sections.py), a strain rod's motion (rod_motion.py); loops closed at t = 0
(assembly.py); named functions of time (profiles.py); ready-made models (chains.py,
mechanisms.py).  It imports the elements, vectors.py and the kernels below it, nothing above."""
