"""The channels of a run: one row per time step, each with its unit and named dimensions.

The same names label the arrays of :class:`orchestrator.run.result.Result` (in memory), the
datasets of a results file (HDF5 dimension scales, so that ``xarray.open_dataset(path,
engine="h5netcdf")`` reads it labelled) and the variables of
:meth:`~orchestrator.run.result.Result.to_xarray`.

Dimensions: ``time`` [s] (the end of each step); ``bearing``, ``mesh``, ``gear`` and ``shaft``,
labelled by the names the case gives them (:class:`gear_fmu.layout.Layout`, the case's order:
the paper's bearings ``1`` .. ``4``, its mesh ``mesh``, its gears ``pinion`` and ``gear``); ``axis``
(``s``, ``t``: the global frame of the gear train). :func:`coordinates` derives the labels from
a case or its layout; nothing here counts bearings or meshes on its own.

>>> from fmu_src.case import load_case
>>> c = coordinates(load_case("two_stage_reducer"))
>>> c["bearing"], c["mesh"]
(('in_a', 'in_b', 'mid_a', 'mid_b', 'out_a', 'out_b'), ('stage1', 'stage2'))
>>> channels(c)["gear_node"][0], dims("gear_node")
((4, 2), ('time', 'gear', 'axis'))
"""

from __future__ import annotations

from fmu_src.units import symbol

__all__ = ["AXES", "DESCRIPTIONS", "UNITS", "channels", "coordinates", "dims"]

#: the labels of the ``axis`` dimension: the global frame's lateral axes
AXES = ("s", "t")

#: channel name -> (dimensions after time, unit's dimension, description)
_TABLE = {
    "journal_position": (("bearing", "axis"), "length",
                         "journal-centre displacement [s, t] at each bearing, global frame"),
    "journal_velocity": (("bearing", "axis"), "velocity",
                         "journal-centre velocity [s_dot, t_dot] at each bearing, global frame"),
    "bearing_force": (("bearing", "axis"), "force",
                      "film force on the journal [F_s, F_t] at each bearing, global frame"),
    "mesh_force": (("mesh",), "force", "total normal force of each mesh (sum of slice loads)"),
    "transmission_error": (("mesh",), "length",
                           "r_b1 theta1 + r_b2 theta2 of each mesh (elastic torsion at its "
                           "gears, driver first)"),
    "gear_node": (("gear", "axis"), "length",
                  "lateral displacement [s, t] of each gear's node, global frame"),
    "shaft_speed": (("shaft",), "angular_speed",
                    "signed speed of each shaft about +z, the imposed rigid-body rotation's "
                    "(drive.speed, or drive.speed_profile at the end of the step)"),
    "iterations": ((), "dimensionless", "coupled master iterations of the step"),
}

#: channel name -> unit symbol (``time``: s)
UNITS = {"time": "s"} | {name: symbol(dim) for name, (_, dim, _) in _TABLE.items()}
#: channel name -> description
DESCRIPTIONS = {"time": "end of the step"} | {name: text for name, (_, _, text) in
                                               _TABLE.items()}


def coordinates(train) -> dict[str, tuple]:
    """The labels of every dimension but time: ``bearing``, ``mesh``, ``gear`` and ``shaft``
    names (the case's order) and ``axis`` (:data:`AXES`), of a :class:`~fmu_src.case.Case` or
    a :class:`~gear_fmu.layout.Layout`."""
    from gear_fmu.layout import Layout

    if not isinstance(train, Layout):
        from fmu_src.description import layout

        train = layout(train)
    return {"bearing": train.bearing_names, "mesh": train.mesh_names,
            "gear": tuple(g.name for g in train.gears),
            "shaft": tuple(s.name for s in train.shafts), "axis": AXES}


def channels(coords: dict) -> dict[str, tuple]:
    """The results channels of a train with these :func:`coordinates`: name -> (shape per
    step, unit, description), as the results writer and the memory recorder take them."""
    return {name: (tuple(len(coords[d]) for d in ds), symbol(dim), text)
            for name, (ds, dim, text) in _TABLE.items()}


def dims(name: str) -> tuple[str, ...]:
    """The dimensions of a channel, ``time`` first (``time`` itself: ``("time",)``);
    KeyError for a name that is no channel."""
    return ("time",) if name == "time" else ("time", *_TABLE[name][0])
