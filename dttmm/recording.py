"""What a DT-TMM run keeps: its samples, gathered as the kernels write them (a block of rows per
chunk, no copy per sample), and its checkpoint, everything a run carries from one step to the
next, to continue it later bit for bit (docs/solver.md, "Steps and records")."""
import json
from dataclasses import dataclass

import numpy as np

# the kernels' state recorded per body (kernels/loop.py::Record), restricted to the model's
# bodies when the kernels integrate more (solver.kernel_model)
_PER_BODY = ("rot", "omega", "omega_dot", "defl", "defl_rate", "jq", "jqd", "jtau", "v_c")


class Recording:
    """The samples of one run: each key's rows in blocks, and the steps they were taken at.
    keep: the kernels' body of each of the model's bodies."""

    def __init__(self, keys, keep):
        self.keys = list(keys)
        self.keep = np.asarray(keep)
        self.inputs = 2 * self.keep + 1             # each body's input station
        self.identity = np.array_equal(self.keep, np.arange(len(self.keep)))
        self.blocks = {key: [] for key in self.keys}
        self.steps = []
        self.times = []         # an adaptive run's sample times (a fixed step's: steps x dt)

    def add(self, values, steps, times=()):
        """values: key -> (m, ...) rows recorded at the m given steps (and times, s, in an
        adaptive run)."""
        for key in self.keys:
            block = values[key]
            if key == "z":                              # the inputs' [m; q] only
                block = block[:, self.inputs, 6:12]
            elif not self.identity and key in _PER_BODY:
                block = block[:, self.keep]
            elif not self.identity and key == "v_st":
                block = block[:, np.append(self.keep, len(self.keep))]
            self.blocks[key].append(np.array(block))     # (a copy: the kernels reuse rec)
        self.steps.extend(steps)
        self.times.extend(times)

    def add_state(self, state, extra, step, t=None):
        """One sample from the state the loop advances (t = 0, the state at the end, or an
        adaptive run's segment end at time t)."""
        values = dict(state._asdict(), **extra)
        self.add({key: values[key][None] for key in self.keys}, [step],
                 () if t is None else [t])

    def arrays(self):
        """key -> all its rows (T, ...), in order; "z" holds the inputs' [m; q] (T, n, 6)."""
        return {key: np.concatenate(blocks) for key, blocks in self.blocks.items()}

    @property
    def last_step(self):
        return self.steps[-1] if self.steps else -1


def leaves(structure):
    """The arrays of nested tuples (the kernels' named tuples), depth first, in order."""
    if isinstance(structure, np.ndarray):
        return [structure]
    if isinstance(structure, tuple):
        return [a for part in structure for a in leaves(part)]
    return []


@dataclass(frozen=True, eq=False)
class Checkpoint:
    """Everything a DT-TMM run carries from one step to the next after `step` steps (t = step
    h): the state, the sweep's and the loop variant's arrays (the fused loops linearize each
    step about the last one's solution), the error monitor and the run's counters.  A run
    continued from it (simulate(..., resume=checkpoint)) takes the same steps on the same
    numbers as the run that wrote it would have: the two halves equal the whole run bit for
    bit.  save(path) / Checkpoint.load(path): a .npz file."""
    step: int
    h: float
    run: dict           # what the continued run must match: scheme, method, mode, loop, ...
    arrays: tuple       # leaves((state, sweep, loop, monitor)), copied
    counters: tuple     # (most Newton iterations used, unconverged steps)

    @property
    def t(self):
        return self.step * self.h

    def save(self, path):
        np.savez_compressed(path, step=self.step, h=self.h, run=json.dumps(self.run),
                            counters=np.array(self.counters),
                            **{f"a{i}": a for i, a in enumerate(self.arrays)})

    @classmethod
    def load(cls, path):
        with np.load(path, allow_pickle=False) as data:
            n = sum(1 for name in data.files if name.startswith("a"))
            return cls(step=int(data["step"]), h=float(data["h"]),
                       run=json.loads(str(data["run"])),
                       arrays=tuple(data[f"a{i}"] for i in range(n)),
                       counters=tuple(int(c) for c in data["counters"]))

    def restore(self, structures, run):
        """Copy the arrays into a new run's structures (state, sweep, loop, monitor), after
        checking that the run is the one this checkpoint continues."""
        for key, value in self.run.items():
            if run.get(key) != value:
                raise ValueError(f"simulate(resume=...): the checkpoint was written by a run "
                                 f"with {key} = {value!r}; this run has {run.get(key)!r} (resume "
                                 f"with the same model, dt, scheme, method and options)")
        targets = leaves(structures)
        if len(targets) != len(self.arrays) or any(
                t.shape != a.shape for t, a in zip(targets, self.arrays)):
            raise ValueError("simulate(resume=...): the checkpoint's arrays do not fit this run's "
                             "model (another model?)")
        for target, value in zip(targets, self.arrays):
            target[...] = value

    @classmethod
    def of(cls, step, h, run, structures, counters):
        return cls(step=int(step), h=float(h), run=dict(run),
                   arrays=tuple(a.copy() for a in leaves(structures)),
                   counters=tuple(int(c) for c in counters))
