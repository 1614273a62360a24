"""What a run gives back (docs/README.md, "Layout"): the Result (result.py) with the
quantities derived from its samples, the samples and checkpoints as the kernels write them
(recording.py), figures and animations (plots.py), and what a run tells its user while it works
(feedback.py).  Below the solving layer, which fills them: it imports the model, the kernels,
the elements and vectors.py, nothing above."""
