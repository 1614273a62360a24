"""Small dense algebra and rotations, compiled: 3 x 3 products and inverses by loops (mat3.py),
SO(3)'s exponential, logarithm and Jacobians (so3.py)."""
