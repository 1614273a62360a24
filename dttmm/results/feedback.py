"""What a run tells its user while it works: a note when the numba kernels are being compiled
(once per install: every kind of model runs them; later runs load them from numba's cache)
and a progress bar on runs that take more than a couple of seconds."""
import os
import sys
import threading
import time

from numba.core import event as numba_event

from ..kernels import compiled_dttmm_function

COMPILE_NOTICE_AFTER = 3.0      # s a compilation runs before stderr says so
COMPILE_REPORT_EVERY = (5.0, 30.0)  # s between its progress reports (a terminal: one line
                                    # rewritten in place; else lines)
PROGRESS_AFTER = 2.0            # s a run is expected to take before it shows a bar


class _CompileWatch(numba_event.Listener):
    """Says on stderr what is compiling and for how long (issue 30): numba announces each
    compilation ("numba:compile" events, outermost first; a kernel loaded from numba's cache
    announces none), and one watcher thread per process, started at the first, writes a line
    once a compilation of dttmm's kernels has run COMPILE_NOTICE_AFTER seconds (the first in
    a process says what compiling is and costs, a later one only its kernels), then the
    seconds so far every COMPILE_REPORT_EVERY (on a terminal one line rewritten in place), and
    a last line when it ends.  Nothing per call: a run whose kernels are compiled costs no
    thread and no timer."""

    def __init__(self):
        self.depth = 0
        self.active = None             # (what, start time) of the outermost compilation
        self.announced = False
        self.explained = False          # the first notice in a process says what compiling is
        self.next_at = 0.0              # when the watcher writes its next line
        self.ending = ""                # what the last line starts with ("\r": rewrite)
        self.wake = threading.Condition()
        self.thread = None

    def on_start(self, event):
        self.depth += 1
        if self.depth > 1:
            return
        function = compiled_dttmm_function(event)
        if function is None:
            return                      # (a user's own numba function: not ours to report)
        with self.wake:
            t0 = time.perf_counter()
            # (a kernel's copy for a model's features is named kernel__features,
            # kernels/features.py: the notice names the kernel)
            self.active = (function.__name__.split("__")[0], t0)
            self.announced = False
            self.next_at = t0 + COMPILE_NOTICE_AFTER
            if self.thread is None:
                self.thread = threading.Thread(target=self._watch, daemon=True,
                                               name="dttmm-compile-watch")
                self.thread.start()
            self.wake.notify()

    def on_end(self, event):
        self.depth -= 1
        if self.depth > 0 or self.active is None:
            return
        with self.wake:
            what, t0 = self.active
            if self.announced:
                _say(f"{self.ending}dttmm: compiled {what} in {time.perf_counter() - t0:.0f} s "
                     f"(cached for later runs)")
            self.active = None
            self.wake.notify()

    def _watch(self):
        with self.wake:
            while True:
                active = self.active
                if active is None:
                    self.wake.wait()
                    continue
                self.wake.wait(max(0.0, self.next_at - time.perf_counter()))
                now = time.perf_counter()
                if self.active is not active or now < self.next_at:
                    continue            # (ended, or woken early)
                what, t0 = active
                terminal = sys.stderr.isatty()
                if not self.announced and not self.explained:
                    _say(f"dttmm: compiling the numba kernels ({what}): once per install, "
                         f"for every kind of model (later runs load them from numba's cache; "
                         f"`dttmm compile` compiles them all ahead); one to two minutes on 2 "
                         f"cores, the general loop's in two processes (docs/solver.md, "
                         f"\"Compile time\"). "
                         f"{now - t0:.0f} s so far")
                    self.announced = self.explained = True
                    self.ending = ""
                elif not self.announced:    # (a later one in the same process: one line)
                    _say(f"dttmm: compiling the numba kernels ({what}) too: "
                         f"{now - t0:.0f} s so far")
                    self.announced, self.ending = True, ""
                elif terminal:
                    print(f"\rdttmm: still compiling {what}: {now - t0:.0f} s so far",
                          end="", file=sys.stderr, flush=True)
                    self.ending = "\r"
                else:
                    _say(f"dttmm: still compiling {what}: {now - t0:.0f} s so far")
                self.next_at += COMPILE_REPORT_EVERY[0 if terminal else 1]


def _say(text):
    print(text, file=sys.stderr, flush=True)


_noted = set()


def note_once(key, text):
    """Say text on stderr the first time key is noted in this process."""
    if key not in _noted:
        _noted.add(key)
        _say(text)


_watch = _CompileWatch()
numba_event.register("numba:compile", _watch)
# a forked child (a process pool) has no watcher thread and may have copied the condition
# locked: it starts afresh
os.register_at_fork(after_in_child=lambda: _watch.__init__())


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
