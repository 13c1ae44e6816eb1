"""The progress line's time left: the rate since the first line that showed work, so that a
first block slowed by one-off costs (numba's compilation on a first run) does not inflate the
estimate for the rest of the run."""

from __future__ import annotations

import io

from orchestrator.run import progress as progress_module
from orchestrator.run.progress import Progress


def test_the_time_left_counts_from_the_first_work_shown(monkeypatch):
    """A first block of 1000 steps in 20 s (compiling), then 100 steps/s: at 3000 of 65,536
    steps the line says (65,536 - 3000) / 100 = 625.4 s left, where the average since the
    start says 833.8 s; the first line, with no rate yet, says "?"."""
    clock = [0.0]
    monkeypatch.setattr(progress_module.time, "perf_counter", lambda: clock[0])
    out = io.StringIO()  # not a terminal: a line every 10 s at most
    bar = Progress(65536, "run", stream=out)
    for t, done in ((20.0, 1000), (40.0, 3000), (45.0, 3500), (70.0, 65536)):
        clock[0] = t
        bar.update(done)
    lines = out.getvalue().splitlines()
    assert len(lines) == 3  # the update at 45 s came within 10 s of the last line
    assert lines[0].rstrip().endswith("20.0 s,      ? s left")
    assert lines[1].rstrip().endswith("40.0 s,  625.4 s left")
    assert lines[2].rstrip().endswith("70.0 s,    0.0 s left")


def test_the_last_line_is_written_once():
    """The run's loop and its end both report the last step: one line says so, in a log
    (not a terminal) as on a terminal."""
    for tty in (False, True):
        out = io.StringIO()
        out.isatty = lambda tty=tty: tty
        bar = Progress(64, "run", stream=out)
        bar.update(64, "2.00 it/step")
        bar.update(64, "2.00 it/step")
        assert out.getvalue().count("64/64") == 1, out.getvalue()
