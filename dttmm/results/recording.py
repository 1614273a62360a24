"""What a DT-TMM run keeps: its samples, gathered as the kernels write them (a block of rows per
chunk, no copy per sample), and its checkpoint, everything a run carries from one step to the
next, to continue it later bit for bit (docs/solver.md, "Steps and records")."""
import hashlib
import json
import os
from dataclasses import dataclass, field, fields

import numpy as np

# the kernels' state recorded per body (kernels/stepping/loop.py::Record), restricted to the model's
# bodies when the kernels integrate more (run_tables.kernel_model)
_PER_BODY = ("rot", "omega", "omega_dot", "defl", "defl_rate", "jq", "jqd", "jtau", "v_c")


class RecordLayout:
    """What a run records, the same for every run of a prepared run (solving/run_plan.py), so
    made once: the keys; each key's pick of the model's bodies from the kernels' rows (keep:
    the kernels' body of each of the model's bodies; identity: whether those are every kernel
    body, in order; default: keep is 0 .. n - 1; a kernel model with bodies of its own after
    the model's needs False, run_plan's keeps_every_body); and, given the run's state and its
    other recorded arrays (extra: the histories), the arrays a sample of the state is read
    from, the loop writing them in place for the whole run (a short run's first and last
    sample cost one copy per key)."""

    def __init__(self, keys, keep, identity=None, state=None, extra=None):
        self.keys = list(keys)
        self.keep = np.asarray(keep)
        self.identity = (np.array_equal(self.keep, np.arange(len(self.keep))) if identity is None
                         else identity)
        # each key's rows of the model's bodies: "z" holds each body's input station's [m; q]
        # (station 2k + 1), the per-body keys the kept bodies (all of them: every row)
        every = slice(None)
        inputs = slice(1, 2 * len(self.keep), 2) if self.identity else 2 * self.keep + 1
        self.picks = {"z": (every, inputs, slice(6, 12))}
        if not self.identity:
            self.picks.update({key: (every, self.keep) for key in _PER_BODY})
            self.picks["v_st"] = (every, np.append(self.keep, len(self.keep)))
        self.state_arrays = self.state_rows = None
        if state is not None:
            # (key, the state's or extra's array), and (key, its row as recorded, pick): the
            # row picked once where the pick is slices (a view), else picked at each sample
            self.state_arrays = [(key, extra[key] if key in extra else getattr(state, key))
                                 for key in self.keys]
            self.state_rows = []
            for key, value in self.state_arrays:
                pick = self.picks[key][1:] if key in self.picks else None
                if pick is not None and all(isinstance(p, slice) for p in pick):
                    value, pick = value[pick], None
                row = value if pick is None else value[pick]
                self.state_rows.append((key, value, pick, row.shape, row.dtype))


class Recording:
    """The samples of one run: each key's rows in blocks, and the steps they were taken at.
    layout: what it records (RecordLayout); stream: a SampleStream to write the rows to instead
    of keeping them (simulate(..., stream=path)).  samples: how many rows the run will record,
    where known (a fixed-step run): each key's rows are then written into one array of that
    many rows, which is never joined (a join holds a key's rows twice); more rows than that go
    on in blocks."""

    def __init__(self, layout, stream=None, samples=None):
        self.layout = layout
        self.keys, self.picks = layout.keys, layout.picks
        self.steps = []
        self.times = []         # an adaptive run's sample times (a fixed step's: steps x dt)
        self.stream = stream
        self.samples = samples
        self.rows = 0           # rows written into the arrays of `samples` rows
        self._rows_of_state = None  # (add_state's value, pick and array of samples per key)
        if stream is None and samples is not None and layout.state_rows is not None:
            # each key's array of `samples` rows, made now (its row's shape is the state's)
            self.blocks = {key: [np.empty((samples,) + shape, dtype)]
                           for key, _, _, shape, dtype in layout.state_rows}
            self._rows_of_state = [(value, pick, self.blocks[key][0])
                                   for key, value, pick, _, _ in layout.state_rows]
        else:
            self.blocks = {key: [] for key in self.keys}

    @classmethod
    def from_stream(cls, path):
        """The recording a run streamed to path (its samples so far, if it stopped)."""
        stream = SampleStream.open(path)
        recording = cls(RecordLayout(stream.meta["keys"], np.arange(0)), stream)
        recording.steps, recording.times = stream.steps_and_times()
        return recording

    def add(self, values, steps, times=()):
        """values: key -> (m, ...) rows recorded at the m given steps (and times, s, in an
        adaptive run)."""
        picks, rows, end = self.picks, self.rows, self.rows + len(steps)
        into = self.stream is None and self.samples is not None and end <= self.samples
        for key in self.keys:
            block = values[key]
            pick = picks.get(key)
            if pick is not None:
                block = block[pick]
            if self.stream is not None:
                self.stream.write(key, block)
            elif into:
                self._samples_of(key, block.shape[1:], block.dtype)[rows:end] = block
            else:
                self._leave_samples()
                self.blocks[key].append(np.array(block))     # (a copy: the kernels reuse rec)
        if self.samples is not None:
            self.rows = end
        self.steps.extend(steps)
        self.times.extend(times)
        if self.stream is not None:
            self.stream.commit(steps, times)

    def _samples_of(self, key, shape, dtype):
        """The key's array of `samples` rows of this shape and dtype, made at its first row."""
        blocks = self.blocks[key]
        if not blocks:
            blocks.append(np.empty((self.samples,) + shape, dtype))
        return blocks[0]

    def add_state(self, step, t=None):
        """One sample of the run's state (its layout's state_rows, as the loop left them: t = 0,
        the state at the end, or an adaptive run's segment end at time t)."""
        if self._rows_of_state is None or self.samples is None or self.rows >= self.samples:
            self.add({key: value[None] for key, value in self.layout.state_arrays}, [step],
                     () if t is None else [t])
            return
        row = self.rows                         # (written in place: a short run's first and
        for value, pick, samples in self._rows_of_state:    # last sample cost a copy a key)
            samples[row] = value if pick is None else value[pick]
        self.rows += 1
        self.steps.append(step)
        if t is not None:
            self.times.append(t)

    def arrays(self):
        """key -> all its rows (T, ...), in order; "z" holds the inputs' [m; q] (T, n, 6).
        Streamed: read-only memory maps of the stream's files."""
        if self.stream is not None:
            return self.stream.arrays()
        if self.samples is not None and self.rows == self.samples:     # (every row said)
            return {key: blocks[0] for key, blocks in self.blocks.items()}
        self._leave_samples()
        for key, blocks in self.blocks.items():     # one key at a time into one block, each
            if len(blocks) > 1:                     # block released once copied (the samples'
                joined = np.empty((sum(map(len, blocks)),) + blocks[0].shape[1:],  # memory is
                                  blocks[0].dtype)                           # never held twice)
                row = 0
                while blocks:
                    block = blocks.pop(0)
                    joined[row:row + len(block)] = block
                    row += len(block)
                    del block
                blocks.append(joined)
        return {key: blocks[0] for key, blocks in self.blocks.items()}

    def _leave_samples(self):
        """From the arrays of `samples` rows to blocks: the rows written so far become each
        key's first block (a run that records more rows than it said, or has stopped)."""
        if self.samples is not None:
            for blocks in self.blocks.values():
                if blocks:
                    blocks[0] = blocks[0][:self.rows]
            self.samples = None

    @property
    def last_step(self):
        return self.steps[-1] if self.steps else -1


class SampleStream:
    """A run's samples written to a directory as they are recorded (docs/solver.md, "Steps and
    records"): one raw file per key, rows appended (KEY.bin), the steps (and an adaptive run's
    times) likewise, and index.json (keys, dtypes, row shapes, rows written, the run's dt and
    info), rewritten after each block, so that the samples of a run that stops or is killed
    stay readable (dttmm.load_stream).  The run's memory then holds no samples at all."""

    INDEX = "index.json"

    def __init__(self, path, meta):
        self.path, self.meta = str(path), dict(meta)
        self.meta.setdefault("rows", 0)
        self.meta.setdefault("layout", {})

    @classmethod
    def create(cls, path, keys, dt, info):
        """A new stream at path (a directory, created; a stream already there is replaced)."""
        path = str(path)
        if os.path.exists(path) and not os.path.isdir(path):
            raise ValueError(f"simulate: stream must name a directory, and {path!r} is a file")
        os.makedirs(path, exist_ok=True)
        # a stream already there is replaced; anything else in the directory is left alone,
        # and a directory holding other files is refused (they might be a user's)
        ours = {cls.INDEX, "_steps.bin", "_times.bin"}
        if os.path.isfile(os.path.join(path, cls.INDEX)):
            try:
                with open(os.path.join(path, cls.INDEX)) as fh:
                    ours |= {f"{key}.bin" for key in json.load(fh).get("layout", {})}
            except (OSError, ValueError):
                pass
        others = sorted(set(os.listdir(path)) - ours - {cls.INDEX + ".new"})
        if others:
            raise ValueError(f"simulate: the stream directory {path!r} holds files that are not "
                             f"a stream's ({', '.join(others[:3])}"
                             f"{', ...' if len(others) > 3 else ''}): give a new or empty "
                             f"directory")
        for name in os.listdir(path):
            os.remove(os.path.join(path, name))
        stream = cls(path, dict(keys=list(keys), dt=dt, info=info))
        stream._write_index()
        return stream

    @classmethod
    def open(cls, path):
        index = os.path.join(str(path), cls.INDEX)
        if not os.path.isfile(index):
            raise ValueError(f"load_stream: {str(path)!r} holds no stream ({cls.INDEX} is "
                             f"missing: was it written by simulate(..., stream=path)?)")
        with open(index) as fh:
            return cls(path, json.load(fh))

    def _file(self, key):
        return os.path.join(self.path, f"{key}.bin")

    def write(self, key, block):
        block = np.ascontiguousarray(block)
        self.meta["layout"].setdefault(key, [block.dtype.str, list(block.shape[1:])])
        with open(self._file(key), "ab") as fh:
            fh.write(block.tobytes())

    def commit(self, steps, times):
        """After a block's keys: its steps (and times), then the index with the new count."""
        for key, values, dtype in (("_steps", steps, np.int64), ("_times", times, np.float64)):
            if len(values):
                with open(self._file(key), "ab") as fh:
                    fh.write(np.asarray(values, dtype=dtype).tobytes())
        self.meta["rows"] += len(steps)
        self._write_index()

    def _write_index(self):
        temporary = os.path.join(self.path, self.INDEX + ".new")
        with open(temporary, "w") as fh:
            json.dump(self.meta, fh, default=float)
        os.replace(temporary, os.path.join(self.path, self.INDEX))     # (atomic)

    def arrays(self):
        """key -> read-only memory map of its rows (rows, ...)."""
        rows = self.meta["rows"]
        return {key: np.memmap(self._file(key), dtype=np.dtype(dtype), mode="r",
                               shape=(rows, *shape)) if rows * int(np.prod(shape)) else
                np.zeros((rows, *shape), dtype=np.dtype(dtype))        # (nothing to map)
                for key, (dtype, shape) in self.meta["layout"].items()}

    def steps_and_times(self):
        rows = self.meta["rows"]
        steps = np.fromfile(self._file("_steps"), dtype=np.int64, count=rows).tolist()
        times = (np.fromfile(self._file("_times"), dtype=np.float64, count=rows).tolist()
                 if os.path.exists(self._file("_times")) else [])
        return steps, times


def model_fingerprint(model):
    """A short digest of what defines a model (every array field's dtype, shape and bytes,
    every other field's repr, functions by their qualified names): a checkpoint or a stream
    carries its model's and refuses another (docs/solver.md, "Steps and records")."""
    cached = getattr(model, "__dict__", {}).get("_fingerprint")
    if cached is not None:          # (a Model is frozen: its digest is computed once)
        return cached
    digest = hashlib.sha256()

    def feed(value):
        if isinstance(value, np.ndarray):
            digest.update(f"{value.dtype.str}{value.shape}".encode())
            if value.flags.c_contiguous:
                digest.update(value.data)       # (the bytes in place, no copy)
            else:                               # (a shared table's rows, block by block)
                rows = max(1, (1 << 20) // max(1, value[:1].nbytes))
                for i in range(0, len(value), rows):
                    digest.update(np.ascontiguousarray(value[i:i + rows]).data)
        elif isinstance(value, (list, tuple)):
            digest.update(f"[{len(value)}".encode())
            for v in value:
                feed(v)
        elif isinstance(value, dict):
            for key in sorted(value, key=str):
                digest.update(str(key).encode())
                feed(value[key])
        elif callable(value):
            digest.update(getattr(value, "__qualname__", type(value).__name__).encode())
        else:
            digest.update(repr(value).encode())

    for f in fields(model):
        digest.update(f.name.encode())
        feed(getattr(model, f.name))
    fingerprint = digest.hexdigest()[:16]
    if hasattr(model, "__dict__"):
        object.__setattr__(model, "_fingerprint", fingerprint)
    return fingerprint


def _checkpoint_digest(step, h, run, counters, arrays):
    """sha256 of a checkpoint's content: an edited file is refused at load."""
    digest = hashlib.sha256(json.dumps([int(step), repr(float(h)), run,
                                        [int(c) for c in counters]],
                                       sort_keys=True, default=str).encode())
    for a in arrays:
        digest.update(f"{a.dtype.str}{a.shape}".encode())
        digest.update(np.ascontiguousarray(a).tobytes())
    return digest.hexdigest()


class NoCheckpoint:
    """What ``result.checkpoint`` holds for a run that cannot be continued (adaptive steps,
    a Richardson extrapolation): false like None, but passed as ``resume=`` it says why
    instead of the run starting again at t = 0."""

    def __init__(self, why):
        self.why = why

    def __bool__(self):
        return False

    def __repr__(self):
        return f"NoCheckpoint({self.why!r})"

    def save(self, path):
        raise ValueError(f"Checkpoint.save: {self.why}")


def leaves(structure, out=None):
    """The arrays of nested tuples (the kernels' named tuples), depth first, in order."""
    out = [] if out is None else out
    for part in structure:
        if isinstance(part, np.ndarray):
            out.append(part)
        elif isinstance(part, tuple):
            leaves(part, out)
    return out


@dataclass(frozen=True, eq=False)
class Checkpoint:
    """Everything a fixed-step DT-TMM run carries from one step to the next.

    The state, the sweep's and the loop variant's arrays (the fused loops linearize each step
    about the last one's solution), the error monitor and the run's counters after `step`
    steps (t = step h). A run continued from it (``simulate(..., resume=checkpoint)``) takes
    the same steps on the same numbers as the run that wrote it would have: the two halves
    equal the whole run bit for bit. Made by ``simulate`` (``result.checkpoint``), not by hand.

    Parameters
    ----------
    step : int
        Steps taken.
    h : float
        The run's step, s.
    run : dict
        What a continued run must match (scheme, method, mode, loop, dt, bodies, Newton
        iterations).
    counters : tuple of int
        (most Newton iterations used, unconverged steps).
    source : tuple or callable
        The run's structures as it ended, (state, sweep, loop, monitor), or their arrays, or
        a function returning those arrays (a prepared run's copy, solving/run_plan.py): ``arrays``
        gathers them, read-only, when first read (a run that is never resumed or saved pays
        nothing for its checkpoint).

    See Also
    --------
    save, load : keep it in a .npz file.
    """
    step: int
    h: float
    run: dict           # what the continued run must match: scheme, method, mode, loop, ...
    counters: tuple     # (most Newton iterations used, unconverged steps)
    source: object = field(repr=False)  # (state, sweep, loop, monitor), their arrays or a
    #                                     function returning them

    @property
    def t(self):
        return self.step * self.h

    @property
    def arrays(self):
        """The run's arrays as it ended, read-only, in ``leaves((state, sweep, loop,
        monitor))`` order (gathered once, when first read)."""
        gathered = self.__dict__.get("_arrays")
        if gathered is None:
            gathered = tuple(self.source() if callable(self.source) else leaves(self.source))
            for a in gathered:          # the run is over and nothing writes them again
                a.flags.writeable = False
            object.__setattr__(self, "_arrays", gathered)
        return gathered

    def save(self, path):
        """Write the checkpoint to path (a .npz file; Checkpoint.load reads it).

        Parameters
        ----------
        path : str or path
            The file to write.
        """
        np.savez_compressed(path, step=self.step, h=self.h, run=json.dumps(self.run),
                            counters=np.array(self.counters),
                            digest=_checkpoint_digest(self.step, self.h, self.run, self.counters,
                                                      self.arrays),
                            **{f"a{i}": a for i, a in enumerate(self.arrays)})

    @classmethod
    def load(cls, path):
        """The checkpoint that save wrote to path.

        Parameters
        ----------
        path : str or path
            A .npz file written by Checkpoint.save.

        Returns
        -------
        Checkpoint
        """
        where = f"Checkpoint.load({str(path)!r})"
        try:
            with np.load(path, allow_pickle=False) as data:
                n = sum(1 for name in data.files if name.startswith("a"))
                step, h = int(data["step"]), float(data["h"])
                run = json.loads(str(data["run"]))
                arrays = tuple(data[f"a{i}"] for i in range(n))
                counters = tuple(int(c) for c in data["counters"])
                digest = str(data["digest"])
        except FileNotFoundError:
            raise ValueError(f"{where}: no such file") from None
        except Exception as err:            # truncated, not a .npz, a foreign .npz
            raise ValueError(f"{where}: not a checkpoint written by Checkpoint.save "
                             f"({type(err).__name__}: {err})") from None
        if digest != _checkpoint_digest(step, h, run, counters, arrays):
            raise ValueError(f"{where}: the file's content does not match the digest written "
                             f"with it: it was changed after Checkpoint.save wrote it")
        return cls(step=step, h=h, run=run, counters=counters, source=arrays)

    def restore(self, structures, run):
        """Copy the arrays into a new run's structures (state, sweep, loop, monitor), after
        checking that the run is the one this checkpoint continues."""
        mine = self.run.get("model_fingerprint")
        if mine is not None and run.get("model_fingerprint") != mine:
            raise ValueError("simulate(resume=...): the checkpoint was written by a run of "
                             "another model (its fingerprint differs: masses, dimensions, "
                             "joints or loads changed): resume with the model that wrote it")
        for key, value in self.run.items():
            if run.get(key) != value:
                raise ValueError(f"simulate(resume=...): the checkpoint was written by a run "
                                 f"with {key} = {value!r}; this run has {run.get(key)!r} (resume "
                                 f"with the same model, dt, scheme, method and options)")
        targets = leaves(structures)
        if len(targets) != len(self.arrays) or any(
                t.shape != a.shape for t, a in zip(targets, self.arrays)):
            raise ValueError("simulate(resume=...): the checkpoint's arrays do not fit this run's "
                             "(another model, or a checkpoint saved by a dttmm before its run "
                             "data went flat, 2026-12-07: run it again from the start)")
        for target, value in zip(targets, self.arrays):
            target[...] = value

    @classmethod
    def of(cls, step, h, run, structures, counters):
        """The checkpoint of a run that has ended: its own arrays, or a function returning
        their copy (read-only once read; a run of its own is not copied: a million bodies'
        state is not doubled)."""
        checkpoint = object.__new__(cls)      # (the fields known valid: no __init__, a short
        checkpoint.__dict__.update(step=int(step), h=float(h), run=dict(run),  # run's cost)
                                   counters=tuple(map(int, counters)), source=structures)
        return checkpoint
