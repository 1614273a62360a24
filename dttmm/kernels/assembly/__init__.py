"""One step's assembly: the sweeps that solve a chain or tree of affine transfers with its boundary
conditions (sweep.py) and the closing joints held with them (closure.py)."""
