"""One step's assembly: the sweeps that solve a chain or tree of affine transfers with its boundary
conditions (sweep.py: chains; tree_sweep.py: trees) and the closing joints held with them
(closure.py: the rows and the step's solve; loop_columns.py: the sweep's columns;
loop_projection.py: the loops held after a step)."""
