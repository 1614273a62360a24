"""What a run tells its user while it works: a note when the numba kernels are being compiled
(once per machine and kind of model; later runs load them from numba's cache) and a progress
bar on runs that take more than a couple of seconds."""
import sys
import threading
import time

COMPILE_NOTICE_AFTER = 3.0      # s a kernel call may take before it is said to be compiling
PROGRESS_AFTER = 2.0            # s a run is expected to take before it shows a bar

_noticed = False


class compile_notice:
    """Around a first kernel call: if it has not returned after COMPILE_NOTICE_AFTER seconds it
    is compiling, and stderr says so, once per process."""

    def __enter__(self):
        self._timer = None
        if not _noticed:
            self._timer = threading.Timer(COMPILE_NOTICE_AFTER, _say_compiling)
            self._timer.daemon = True
            self._timer.start()
        return self

    def __exit__(self, *exc):
        if self._timer is not None:
            self._timer.cancel()
        return False


def _say_compiling():
    global _noticed
    _noticed = True
    print("dttmm: compiling the numba kernels for this kind of model; this happens once (they "
          "are cached for later runs) and takes about a minute for chains and trees of ball "
          "joints, a few minutes for other joints, on a 2-core machine.",
          file=sys.stderr, flush=True)


class Progress:
    """A tqdm bar over a run's steps, shown once the run is expected to take more than
    PROGRESS_AFTER seconds.  enabled: None (default) shows it only when stderr is a terminal,
    True always, False never."""

    def __init__(self, n_steps, enabled=None, what="dttmm", unit="step"):
        if enabled is None:
            enabled = sys.stderr.isatty()
        self.enabled, self.n_steps, self.what = bool(enabled), n_steps, what
        self.unit = unit
        self._first = None          # (time, steps) after the first chunk (which may compile)
        self._bar = None

    def update(self, done):
        """done: the steps taken so far."""
        if not self.enabled or done <= 0:
            return
        now = time.perf_counter()
        if self._first is None:
            self._first = (now, done)
            return
        if self._bar is None:
            t0, done0 = self._first
            rate = (done - done0) / max(now - t0, 1e-9)          # steps per second
            if (self.n_steps - done0) / max(rate, 1e-9) < PROGRESS_AFTER:
                return
            from tqdm import tqdm
            self._bar = tqdm(total=self.n_steps, initial=done, desc=self.what, unit=self.unit,
                             leave=False, file=sys.stderr)
        else:
            self._bar.update(done - self._bar.n)

    def close(self):
        if self._bar is not None:
            self._bar.close()
            self._bar = None
