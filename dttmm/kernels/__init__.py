"""numba kernels on flat arrays: rotations, element transfer matrices, assembly sweeps, the step."""
