"""The sweep file: one HDF5 file per sweep, written one point at a time
(:mod:`orchestrator.sweeps.runner`).

Between two points the file is closed, complete and readable (``gsb plot`` of a running sweep),
so a killed client loses no finished point. Every dataset carries ``unit`` and ``description``
attributes (:data:`DATASETS`).

* root attributes: ``kind = "sweep"``, ``case`` (name), ``case_file`` (where the client read
  it), ``case_toml`` (the case's text, SI; the points override it), ``vary_keys`` (strings,
  the case fields varied), ``vary_units`` (their SI units), ``bearings`` (the bearing models,
  strings), ``periods`` (mesh periods of every run), ``window`` (the name of the window the
  points' figures are taken over, :func:`orchestrator.sweeps.runner.sweep_window`; a file of an
  earlier version holds ``steady_periods`` instead, that window in mesh periods),
  ``n_points``, ``n_failed``, ``status`` ("running", "complete", "failed points",
  "worker timeout", "scheduler lost", "interrupted"), ``complete`` (true only when every point
  succeeded), ``wall_time`` [s], and the names that label the points' datasets:
  ``bearing_names``, ``bearing_shafts`` (each bearing's shaft), ``mesh_names``;
* a group per point, ``points/<index>``: attributes ``values`` (the varied values in SI units,
  in ``vary_keys`` order; the first entry of a list field), ``bearing``, ``label``,
  ``overrides`` (JSON text, as given), ``error`` and ``traceback`` if it failed, ``warnings``
  (the run's warnings, if any), and the datasets of :data:`DATASETS` if it succeeded.
"""

from __future__ import annotations

import json
import math
import time
from pathlib import Path

import numpy as np

from fmu_src import description
from fmu_src.case import INSTANCE_SECTIONS, Case, CaseError, field_of
from fmu_src.units import DIMENSIONS, symbol
from orchestrator.analysis.spectrum import PAD

__all__ = ["DATASETS", "GRIDDED", "field_unit", "finish", "point_values", "read_sweep",
           "read_sweep_attrs", "store_point", "sweep_dataset", "write_header"]


#: Datasets of a successful point: name -> (unit, description).
#:
#: :meta hide-value:
DATASETS = {
    "R": (symbol("dimensionless"), "dynamic tooth load factor of each mesh (attribute "
                                   "mesh_names): its max force over its static load, steady "
                                   "window"),
    "transmission_error_ptp": (symbol("length"), "peak-to-peak of each mesh's transmission "
                                                 "error, steady window"),
    "force_ptp": (symbol("force"), "peak-to-peak of ||F_b|| at each bearing (attribute "
                                   "bearing_names), steady window"),
    "force_mean": (symbol("force"), "mean of ||F_b|| at each bearing, steady window"),
    "orbit_centre": (symbol("length"), "centre of the ellipse fitted to the orbit [s, t] at "
                                       "each bearing, steady window"),
    "orbit_mean": (symbol("length"), "mean journal position [s, t] at each bearing, steady "
                                     "window"),
    "time": (symbol("time"), "time of the decimated steady-window samples"),
    "orbit": (symbol("length"), "journal position [s, t] at each bearing, steady window, "
                                "decimated"),
    "bearing_force": (symbol("force"), "film force [F_s, F_t] at each bearing, steady window, "
                                       "decimated"),
    "mesh_force": (symbol("force"), "total normal force of each mesh, steady window, "
                                    "decimated"),
    "transmission_error": (symbol("length"), "transmission error of each mesh, steady window, "
                                             "decimated"),
    "static_journal": (symbol("length"), "static journal positions X0 [s, t] at each bearing"),
    "wall_time": (symbol("time"), "wall time of the point on its worker"),
    "iterations_per_step": (symbol("dimensionless"), "coupled iterations per time step"),
    "spectrum_orders": (symbol("dimensionless"), "orders of the spectrum bins (cycles per "
                                                 "revolution of the input shaft), 0 to 3.5 "
                                                 "times the fastest mesh's"),
    "spectrum": (symbol("force"), "peak amplitude of ||F_b|| at each bearing per order, "
                                  f"order 0 the mean (Hann window zero-padded {PAD} times over "
                                  "the full-resolution steady window, a whole number of "
                                  "input revolutions when it holds one; docs/equations.md)"),
    "spectrum_window": (symbol("time"), "start and end of the spectrum's window"),
    "window_s": (symbol("time"), "duration of the steady window (attribute window)"),
}


def _kind(key: str) -> str | None:
    """The kind of a case key or override key (``gears.*.unbalance``), None for no field."""
    try:
        return field_of(key).kind
    except CaseError:
        return None


def field_unit(key: str) -> str:
    """SI unit of a case field (``"1"`` for counts, ``""`` for text, choices and flags)."""
    kind = _kind(key)
    if kind in DIMENSIONS:
        return symbol(kind)
    return "1" if kind == "count" else ""


def _first(base: Case, key: str) -> str:
    """A ``*`` key as its first instance's (``gears.*.unbalance`` -> ``gears.pinion.unbalance``)."""
    section, *rest = key.split(".")
    if len(rest) == 2 and rest[0] == "*":
        names = base.names(section) if section in INSTANCE_SECTIONS else []
        return f"{section}.{names[0]}.{rest[1]}" if names else key
    return key


def point_values(base: Case, overrides: dict, keys) -> list[float]:
    """The varied values of a point in SI units, bounds not checked (the first entry of a list
    field, the first instance's for a ``*`` key; NaN where a value is not a number or not
    readable)."""
    from fmu_src.units import UnitError, parse_quantity

    out = []
    for key in keys:
        value = overrides[key] if key in overrides else base.values.get(_first(base, key))
        if isinstance(value, (list, tuple)):
            value = value[0] if value else math.nan
        kind = _kind(key)
        if kind in DIMENSIONS and isinstance(value, (int, float, str)) \
                and not isinstance(value, bool):
            try:
                value = parse_quantity(value, kind, key)
            except UnitError:
                value = math.nan
        out.append(float(value) if isinstance(value, (int, float)) else math.nan)
    return out


def _open(path: Path, mode: str, wait: float = 30.0):
    """``h5py.File(path, mode)``, retried for ``wait`` s while a reader holds the file's
    lock (``gsb plot`` of a running sweep)."""
    import h5py

    t0 = time.monotonic()
    while True:
        try:
            return h5py.File(path, mode)
        except BlockingIOError:
            if time.monotonic() - t0 > wait:
                raise
            time.sleep(0.2)


def _strings(values):
    import h5py

    return np.array([str(v) for v in values], dtype=h5py.string_dtype())


def write_header(path: Path, base: Case, vary_keys, bearings, periods: int,
                 window: str, n_points: int) -> None:
    """Create the sweep file with its root attributes (module docstring), no point yet."""
    import h5py

    path.parent.mkdir(parents=True, exist_ok=True)
    with h5py.File(path, "w") as f:
        f.attrs["kind"] = "sweep"
        f.attrs["case"] = base.name
        f.attrs["case_file"] = str(base.source)
        f.attrs["case_toml"] = base.to_toml()
        f.attrs["vary_keys"] = _strings(vary_keys)
        f.attrs["vary_units"] = _strings(field_unit(k) for k in vary_keys)
        f.attrs["bearings"] = _strings(bearings)
        f.attrs["periods"] = int(periods)
        f.attrs["window"] = str(window)
        f.attrs["n_points"] = int(n_points)
        f.attrs["n_failed"] = 0
        f.attrs["status"] = "running"
        f.attrs["complete"] = False
        f.attrs["wall_time"] = 0.0
        lay = description.layout(base)
        f.attrs["bearing_names"] = _strings(lay.bearing_names)
        f.attrs["bearing_shafts"] = _strings(b.shaft for b in lay.bearings)
        f.attrs["mesh_names"] = _strings(lay.mesh_names)
        f.create_group("points")


def store_point(path: Path, index: int, point, base: Case, vary_keys, result: dict,
                n_failed: int) -> None:
    """One point's group (module docstring): ``result`` is
    :func:`orchestrator.sweeps.runner.run_point`'s
    (``ok``, ``data`` or ``error``); ``n_failed`` the failed points so far, this one included."""
    with _open(path, "a") as f:
        g = f["points"].create_group(f"{index:04d}")
        g.attrs["overrides"] = json.dumps(point.overrides)
        g.attrs["values"] = np.asarray(point_values(base, point.overrides, vary_keys),
                                       dtype=float)
        g.attrs["bearing"] = point.bearing or description.shared_bearing_model(base) or "mixed"
        g.attrs["label"] = point.label
        if result["ok"]:
            for key, val in result["data"].items():
                d = g.create_dataset(key, data=val)
                unit, doc = DATASETS.get(key, ("", ""))
                d.attrs["unit"] = unit
                d.attrs["description"] = doc
            if result.get("warnings"):
                g.attrs["warnings"] = result["warnings"]
        else:
            g.attrs["error"] = result["error"]
            g.attrs["traceback"] = result.get("traceback", "")
        f.attrs["n_failed"] = int(n_failed)


def finish(path: Path, status: str, complete: bool, wall_time: float) -> None:
    """Record how the sweep ended."""
    with _open(path, "a") as f:
        f.attrs["wall_time"] = float(wall_time)
        f.attrs["status"] = status
        f.attrs["complete"] = bool(complete)


def read_sweep(path) -> list[dict]:
    """The points of a sweep file: dicts with ``overrides``, ``values``, ``bearing``, ``label``,
    ``error`` and the datasets (absent for failed points), in point order."""
    from orchestrator.run.results import open_results

    out = []
    with open_results(path) as f:
        for key in sorted(f["points"]):
            g = f["points"][key]
            d = {"overrides": json.loads(g.attrs["overrides"]), "bearing": g.attrs["bearing"],
                 "label": g.attrs["label"], "error": g.attrs.get("error"),
                 "values": np.asarray(g.attrs.get("values", []), dtype=float),
                 "warnings": g.attrs.get("warnings", "")}
            for name in g:
                d[name] = g[name][()]
            out.append(d)
    return out


def read_sweep_attrs(path) -> dict:
    """The root attributes of a sweep file (:func:`orchestrator.run.results.read_attributes`;
    string arrays as lists of str, numpy scalars as Python numbers)."""
    from orchestrator.run.results import read_attributes

    out = {}
    for key, value in read_attributes(path).items():
        if isinstance(value, np.ndarray) and value.dtype.kind == "O":
            value = [v.decode() if isinstance(v, bytes) else str(v) for v in value]
        elif isinstance(value, np.generic):
            value = value.item()
        out[key] = value
    return out


#: the point datasets a sweep's xarray dataset carries, with the dimensions of one point's
#: (the decimated time series and the spectra, whose lengths change from point to point, stay
#: in the points' groups: :func:`read_sweep`)
GRIDDED = {"R": ("mesh",), "transmission_error_ptp": ("mesh",), "force_ptp": ("bearing",),
           "force_mean": ("bearing",), "orbit_centre": ("bearing", "axis"),
           "orbit_mean": ("bearing", "axis"), "static_journal": ("bearing", "axis"),
           "window_s": (), "wall_time": (), "iterations_per_step": ()}


def _dim(key: str) -> str:
    """A case key as a dimension name (``drive.speed`` -> ``drive_speed``, ``gears.*.unbalance``
    -> ``gears_unbalance``)."""
    return key.replace(".*.", ".").replace(".", "_")


def sweep_dataset(path):
    """A sweep file as an :class:`xarray.Dataset` over its varied fields and bearing models.

    Dimensions: one per varied field (named after its key, ``drive.speed`` -> ``drive_speed``,
    its sorted SI values as coordinate with their ``unit``), then ``bearing_model``, ``mesh``,
    ``bearing`` (the bearings' names) and ``axis`` (s, t). When the points are not a full grid
    of those values, one dimension ``point`` instead, the varied values as coordinates along it.
    Variables: each dataset of :data:`GRIDDED` (unit and description from :data:`DATASETS`),
    ``error`` (the message of a failed point, ``""`` otherwise) and ``ok``; NaN where a point
    failed. Attributes: the file's root attributes (:func:`read_sweep_attrs`).
    """
    import xarray as xr

    attrs = read_sweep_attrs(path)
    points = read_sweep(path)
    keys = list(attrs.get("vary_keys", []))
    units = list(attrs.get("vary_units", [""] * len(keys)))
    models = list(dict.fromkeys(p["bearing"] for p in points))
    sizes = {"mesh": len(attrs["mesh_names"]), "bearing": len(attrs["bearing_names"]),
             "axis": 2}
    values = [sorted({float(p["values"][i]) for p in points}) for i in range(len(keys))]
    grid = [len(v) for v in values] + [len(models)]
    where = [(*(values[i].index(float(p["values"][i])) for i in range(len(keys))),
              models.index(p["bearing"])) for p in points]
    gridded = len(set(where)) == len(points) == int(np.prod(grid))
    if gridded:
        outer = [*(_dim(k) for k in keys), "bearing_model"]
        index = where
    else:
        outer, grid, index = ["point"], [len(points)], [(i,) for i in range(len(points))]
    data = {}
    for name, inner in GRIDDED.items():
        arr = np.full((*grid, *(sizes[d] for d in inner)), np.nan)
        for at, p in zip(index, points, strict=True):
            if name in p:
                arr[at] = p[name]
        unit, doc = DATASETS[name]
        data[name] = ((*outer, *inner), arr, {"units": unit, "description": doc})
    error = np.full(grid, "", dtype=object)
    for at, p in zip(index, points, strict=True):
        error[at] = p["error"] or ""
    data["error"] = (tuple(outer), error, {"description": "why the point failed (\"\": it "
                                                          "succeeded)"})
    data["ok"] = (tuple(outer), error == "")
    coords = {"mesh": list(attrs["mesh_names"]), "bearing": list(attrs["bearing_names"]),
              "axis": ["s", "t"]}
    if gridded:
        for key, unit, vals in zip(keys, units, values, strict=True):
            coords[_dim(key)] = (_dim(key), vals, {"units": unit, "case_key": key})
        coords["bearing_model"] = models
    else:
        for i, (key, unit) in enumerate(zip(keys, units, strict=True)):
            coords[_dim(key)] = ("point", [float(p["values"][i]) for p in points],
                                 {"units": unit, "case_key": key})
        coords["bearing_model"] = ("point", [p["bearing"] for p in points])
    return xr.Dataset(data, coords=coords, attrs=attrs)
