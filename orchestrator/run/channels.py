"""The channels of a run: one row per time step, each with its unit and named dimensions.

The same names label the arrays of :class:`orchestrator.run.result.Result` (in memory), the
datasets of a results file (HDF5 dimension scales, so that ``xarray.open_dataset(path,
engine="h5netcdf")`` reads it labelled) and the variables of
:meth:`~orchestrator.run.result.Result.to_xarray`.

Dimensions: ``time`` [s] (the end of each step), ``bearing`` (1-4: 1, 2 on the pinion shaft,
3, 4 on the gear shaft), ``axis`` (``s``, ``t``: the global frame of the gear system),
``node`` (``pinion``, ``gear``: the two gear nodes) and ``direction`` (``u``, ``v``: their
lateral displacements).
"""

from __future__ import annotations

from fmu_src.units import symbol

__all__ = ["CHANNELS", "COORDS", "dims"]

#: the labels of every dimension but time
COORDS = {
    "bearing": (1, 2, 3, 4),
    "axis": ("s", "t"),
    "node": ("pinion", "gear"),
    "direction": ("u", "v"),
}

#: channel name -> (dimensions after time, unit, description)
_TABLE = {
    "journal_position": (("bearing", "axis"), "length",
                         "journal-centre displacement [s, t] at bearings 1-4, global frame"),
    "journal_velocity": (("bearing", "axis"), "velocity",
                         "journal-centre velocity [s_dot, t_dot] at bearings 1-4, global frame"),
    "bearing_force": (("bearing", "axis"), "force",
                      "film force on the journal [F_s, F_t] at bearings 1-4"),
    "mesh_force": ((), "force", "total normal mesh force (sum of slice loads)"),
    "transmission_error": ((), "length",
                           "r_b1 theta1 + r_b2 theta2 (elastic torsion at the gears)"),
    "gear_nodes": (("node", "direction"), "length", "[u, v] of the pinion and gear nodes"),
    "iterations": ((), "dimensionless", "coupled master iterations of the step"),
}

#: results channels: name -> (shape per step, unit, description), as the results writer takes
CHANNELS = {name: (tuple(len(COORDS[d]) for d in ds), symbol(dim), text)
            for name, (ds, dim, text) in _TABLE.items()}


def dims(name: str) -> tuple[str, ...]:
    """The dimensions of a channel, ``time`` first (``time`` itself: ``("time",)``)."""
    return ("time",) if name == "time" else ("time", *_TABLE[name][0])
