"""What a long run shows and how it stops: the progress line, what a first run builds or
compiles (:func:`startup_log`), and SIGINT/SIGTERM held until the end of the current step
(:class:`RunInterrupted` then carries the shell's exit code)."""

from __future__ import annotations

import contextlib
import logging
import math
import signal
import sys
import threading
import time

__all__ = ["Progress", "RunInterrupted", "deferred_signals", "startup_log"]


@contextlib.contextmanager
def startup_log(show: bool, always: bool = False):
    """Print the ``gsb.startup`` log (the FMU build, the native layer, numba's compilation:
    what makes a first run slow; silent by default, as a library's log) on stderr as
    ``gsb: <message>`` while the block runs, then give the logger back as it found it.
    ``always`` (the command line, unless ``--quiet``): whatever the caller's logging, which
    then does not get the records too; else (the API) only when nothing would show them: no
    handler of the log's own, none on the root logger it propagates to."""
    log = logging.getLogger("gsb.startup")
    quiet = log.handlers or (log.propagate and logging.getLogger().handlers)
    if not show or (quiet and not always):
        yield
        return
    handler = logging.StreamHandler(sys.stderr)
    handler.setFormatter(logging.Formatter("gsb: %(message)s"))
    level, propagate = log.level, log.propagate
    log.setLevel(logging.INFO)  # setLevel, not .level: it clears the loggers' caches
    log.propagate = False
    log.addHandler(handler)
    try:
        yield
    finally:
        log.removeHandler(handler)
        log.setLevel(level)
        log.propagate = propagate


class RunInterrupted(RuntimeError):
    """A run stopped by SIGINT (Ctrl-C) or SIGTERM between two steps; ``exit_code`` is the
    shell's convention, 128 + the signal number (130, 143)."""

    def __init__(self, signum: int, message: str):
        super().__init__(message)
        self.signum = signum
        self.exit_code = 128 + int(signum)


@contextlib.contextmanager
def deferred_signals(signals=(signal.SIGINT, signal.SIGTERM),
                     stopping: str = "stopping after the current step"):
    """Hold SIGINT and SIGTERM in a list instead of raising where they land.

    A KeyboardInterrupt raised inside an FMU's Python code (pythonfmu runs it in this
    interpreter) is fatal for that FMU and often for the process, and Dask's waits can swallow
    one; the run (and a sweep's gather loop) checks the list between steps instead and stops
    cleanly there. ``stopping`` is what the first signal's message says happens next. Only the
    main thread can install handlers: elsewhere (a Dask worker thread) the list stays empty and
    signals keep their handlers."""
    received: list[int] = []
    if threading.current_thread() is not threading.main_thread():
        yield received
        return

    def hold(signum, frame):
        if not received:
            print(f"\n{signal.Signals(signum).name} received: {stopping} (again to stop at "
                  "once)", file=sys.stderr, flush=True)
        elif signum == signal.SIGINT:  # a second Ctrl-C: the user insists
            raise KeyboardInterrupt
        received.append(signum)

    previous = {s: signal.signal(s, hold) for s in signals}
    try:
        yield received
    finally:
        for s, handler in previous.items():
            signal.signal(s, handler)


class Progress:
    """A one-line progress display on stderr, refreshed at most every ``every`` seconds; on a
    stream that is not a terminal (a log file), one line every 10 s instead.

    The time left is the work left at the rate since the first line that showed work done
    ("?" before a second such line): the first block of a run carries its one-off costs (the
    numba kernels compiled on a first run, the FMUs' first calls), which the average since the
    start would spread over the whole run (12.6 s for the first 128 steps of a first run
    through the FMUs, then 9 s for the other 65,408)."""

    def __init__(self, total: int, label: str = "", every: float = 0.5, stream=None,
                 enabled: bool = True):
        self.total = total
        self.label = label
        self.stream = sys.stderr if stream is None else stream
        self.tty = bool(getattr(self.stream, "isatty", lambda: False)())
        self.every = every if self.tty else max(every, 10.0)
        self.enabled = enabled
        self.start = time.perf_counter()
        self._last = -math.inf
        self._first: tuple[float, int] | None = None  # (time [s], done) of the first work shown
        self._finished = False  # the last line (done >= total) was written

    def update(self, done: int, extra: str = "") -> None:
        if not self.enabled:
            return
        now = time.perf_counter()
        if now - self._last < self.every and done < self.total:
            return
        if done >= self.total:  # the last line once, however many callers reach the end
            if self._finished:
                return
            self._finished = True
        self._last = now
        elapsed = now - self.start
        frac = done / self.total if self.total else 1.0
        eta = self._time_left(now, done)
        left = f"{eta:6.1f}" if math.isfinite(eta) else f"{'?':>6}"
        bar = "#" * int(30 * frac)
        line = (f"{self.label} [{bar:<30}] {done}/{self.total} {100 * frac:5.1f} % "
                f"{elapsed:6.1f} s, {left} s left {extra}")
        if self.tty:
            self.stream.write(f"\r{line}   " + ("\n" if done >= self.total else ""))
        else:
            self.stream.write(line + "\n")
        self.stream.flush()

    def _time_left(self, now: float, done: int) -> float:
        """Seconds left at the rate since the first line that showed work (class docstring);
        inf while there is no such rate yet."""
        if done >= self.total:
            return 0.0
        if self._first is None:
            if done > 0:
                self._first = (now, done)
            return math.inf
        t0, d0 = self._first
        if done <= d0 or now <= t0:
            return math.inf
        return (self.total - done) * (now - t0) / (done - d0)
