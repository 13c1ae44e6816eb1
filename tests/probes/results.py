"""Probe of tests/orchestrator/run/test_results.py: a process killed while it writes a results
file (no clean-up at all)."""

from __future__ import annotations

import os

from tests.probes import dispatch, probes_of


def killed_writer(path: str) -> None:
    """12 rows appended in blocks of 5 (no flush by time), then ``os._exit(9)``."""
    from orchestrator.run.results import ResultsWriter

    w = ResultsWriter(path, {"x": ((), "m", "x")}, capacity=5, flush_seconds=1e9)
    for k in range(12):
        w.append(time=float(k), x=float(k))
    os._exit(9)


PROBES = probes_of(killed_writer)


def main(argv: list[str] | None = None) -> None:
    dispatch(PROBES, argv)


if __name__ == "__main__":
    main()
