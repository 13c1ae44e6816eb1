"""A run's result in memory: the channels with named dimensions, the settings and the report.

:func:`orchestrator.api.simulate` returns a :class:`Result`; :meth:`Result.from_file` reads one
from a results file. The channels and their dimensions are those of
:mod:`orchestrator.run.channels` (``time``, ``bearing``, ``mesh`` and ``gear`` by the case's
names, ``axis`` s/t), and :meth:`Result.to_xarray` labels them:

>>> import numpy as np
>>> r = Result({"time": np.array([1e-4, 2e-4]),
...             "mesh_force": np.array([[2250.0], [2260.0]])}, {"case": "demo"},
...            coords={"mesh": ("mesh",)})
>>> float(r["mesh_force"].max())
2260.0
>>> r.to_xarray().mesh_force.sel(time=2e-4, mesh="mesh").item()
2260.0
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from orchestrator.run.channels import DESCRIPTIONS, UNITS, coordinates, dims

__all__ = ["MemoryRecorder", "Result"]


@dataclass
class Result:
    """The channels of a run (``time`` [s] first; arrays with ``time`` as first axis), the run's
    settings and report (``attrs``: the root attributes a results file would hold, numbers in
    SI units, each unit in ``<name>_unit``), for a run of this process its
    :class:`~orchestrator.run.runner.RunSummary` (``summary``; None when read from a file) and
    ``coords``, the labels of the dimensions (:func:`orchestrator.run.channels.coordinates`;
    None: those of the case stored in ``attrs["case_toml"]``)."""

    channels: dict[str, np.ndarray]
    attrs: dict = field(default_factory=dict)
    summary: object = None
    coords: dict | None = None

    def __repr__(self) -> str:
        """A few lines: the case, the steps, each channel's shape, R (the arrays are in
        ``channels``)."""
        time = self.channels.get("time", np.empty(0))
        name = self.attrs.get("case", "a run")
        lines = [f"Result of {name}: {time.size} steps"
                 + (f" to t = {float(time[-1]):.6g} s" if time.size else "")]
        lines += [f"  {n} {tuple(np.shape(a))}" for n, a in self.channels.items() if n != "time"]
        report = self.report
        if report is not None and "dynamic_factor" in report:
            r = ", ".join(f"{float(v):.4g}" for v in np.atleast_1d(report["dynamic_factor"]))
            lines.append(f"  dynamic factor R = {r}")
        return "\n".join(lines)

    def __getitem__(self, name: str) -> np.ndarray:
        try:
            return self.channels[name]
        except KeyError:
            raise KeyError(f"no channel {name!r}; the result has "
                           f"{', '.join(self.channels)}") from None

    @property
    def time(self) -> np.ndarray:
        """The end time of each step [s]."""
        return self.channels["time"]

    @property
    def report(self) -> dict | None:
        """:func:`orchestrator.analysis.metrics.run_report` of the run (None below 2 steps)."""
        return None if self.summary is None else self.summary.report

    def as_dict(self) -> dict:
        """The form :func:`orchestrator.run.results.read_results` gives (channels, ``units``,
        ``attrs``), which the analysis functions take."""
        units = {n: UNITS.get(n, "") for n in self.channels}
        return {**self.channels, "units": units, "attrs": dict(self.attrs),
                "coords": self.coordinates()}

    def coordinates(self) -> dict:
        """The labels of the dimensions (``coords``, else those of the stored case)."""
        if self.coords is None:
            from orchestrator.analysis.metrics import stored_case

            self.coords = coordinates(stored_case(self.attrs))
        return self.coords

    def to_xarray(self):
        """An :class:`xarray.Dataset`: one variable per channel on its named dimensions,
        the labels of ``bearing``, ``mesh``, ``gear`` and ``axis`` as coordinates, the units in
        each variable's ``units`` attribute and the settings as its attributes."""
        import xarray as xr

        variables = {}
        for name, values in self.channels.items():
            if name == "time":
                continue
            variables[name] = (dims(name), np.asarray(values),
                               {"units": UNITS[name], "description": DESCRIPTIONS[name]})
        used = {d for name in variables for d in dims(name)}
        coords = {"time": ("time", self.time, {"units": UNITS["time"],
                                               "description": DESCRIPTIONS["time"]})}
        coords |= {d: (d, [str(x) for x in labels]) for d, labels in self.coordinates().items()
                   if d in used}
        return xr.Dataset(variables, coords=coords, attrs=_as_stored(self.attrs))

    @classmethod
    def from_file(cls, path) -> Result:
        """The channels and settings of a results file (all the rows written so far)."""
        from orchestrator.run.results import read_results

        data = read_results(path)
        attrs = data.pop("attrs")
        coords = data.pop("coords")
        data.pop("units")
        return cls(data, attrs, coords=coords or None)


def _as_stored(attrs: dict) -> dict:
    """The attributes as xarray reads them from a results file: written to an HDF5 file in
    memory as the results writer writes them
    (:func:`orchestrator.run.results.attribute_value`), read back by xarray's ``h5netcdf``
    engine (numbers as numpy scalars, a one-element array as its element, arrays of any rank
    kept): a run's :meth:`Result.to_xarray` and its file's dataset are then identical."""
    import io

    import h5py
    import xarray as xr

    from orchestrator.run.results import attribute_value

    buffer = io.BytesIO()
    with h5py.File(buffer, "w") as f:
        for key, value in attrs.items():
            f.attrs[key] = attribute_value(value)
    buffer.seek(0)
    with xr.open_dataset(buffer, engine="h5netcdf") as ds:
        return dict(ds.attrs)


class MemoryRecorder:
    """Keeps the rows of a run in memory; the same ``append``/``close`` as
    :class:`orchestrator.run.results.ResultsWriter`, so the runner writes to either."""

    def __init__(self, channels: dict, attrs: dict | None = None, coords: dict | None = None):
        self.channel_shapes = {"time": ()} | {n: shape for n, (shape, _, _) in channels.items()}
        self._rows: dict[str, list] = {n: [] for n in self.channel_shapes}
        self.attrs = dict(attrs or {})
        self.coords = coords
        self.rows = 0

    def append(self, **row) -> None:
        for name, rows in self._rows.items():
            rows.append(np.array(row[name], dtype=float))
        self.rows += 1

    def append_rows(self, count: int, flush: bool = True, **rows) -> None:
        """``count`` rows at once, each channel ``(count, *shape)`` (``flush`` has no use in
        memory)."""
        for name, kept in self._rows.items():
            kept.extend(np.asarray(rows[name], dtype=float).reshape(
                count, *self.channel_shapes[name]))
        self.rows += count

    def close(self, complete: bool = True, checkpoint: bool = True, **attrs) -> None:
        self.attrs |= {"complete": bool(complete), **attrs}

    def result(self, summary=None) -> Result:
        channels = {n: (np.array(rows) if rows else np.empty((0, *self.channel_shapes[n])))
                    for n, rows in self._rows.items()}
        return Result(channels, self.attrs, summary, self.coords)
