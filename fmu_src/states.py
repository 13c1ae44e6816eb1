"""The states of the physics objects as flat arrays (:mod:`fmu_src.state_codec`), and back.

What a checkpoint or a serialised FMU state holds of the structure and of the bearing models,
entry by entry; restoring checks every entry against the object it restores (dtype, shape, the
sizes of its case), so that no array of the wrong size reaches a compiled kernel.

Structure (:class:`gear_fmu.structure.StructureState`):

* ``t`` float64, ``n_steps`` int64, ``x``, ``v``, ``a`` float64 (n_dof,);
* ``mesh/<m>/...`` each mesh's state at the last solution
  (:class:`gear_fmu.mesh.element.MeshState`; m = 0, 1, ... in the layout's order), absent
  before one: ``force`` (12,), ``stiffness`` (12, 12), ``delta``, ``load``, ``xi``, ``z``
  float64 (n_slices,), ``active``, ``inside`` bool (n_slices,), ``total_load``,
  ``transmission_error`` and ``extra/<name>`` float64 scalars.

Bearing models (their ``get_state``; nothing for a model without memory):

* finite differences: ``p`` float64 (the multigrid pressure), ``have_p`` bool, ``active`` bool
  (n_theta (n_xi - 1),) (the direct solver's active set, absent until it has one);
* hybrid: ``record/<field>`` one entry per field of the solver's state record, ``active`` bool
  (n,);
* linearised: ``film/...`` its film model's, and once frozen ``law/position0`` (2,),
  ``law/force0`` (2,), ``law/stiffness``, ``law/damping`` (2, 2), ``law/omega``.

Affine laws (:class:`bearing_fmu.affine.AffineLaws`): ``f0`` (nb, 2), ``kb``, ``cb``
(nb, 2, 2), and when known ``states`` (nb, 4), ``force_at`` (nb, 2).
"""

from __future__ import annotations

import numpy as np

from bearing_fmu.affine import AffineLaws
from bearing_fmu.base import BearingModel
from bearing_fmu.fd.model import FiniteDifferenceBearing
from bearing_fmu.hybrid.model import HybridBearing
from bearing_fmu.linear import LinearisedBearing
from fmu_src.state_codec import StateArrays, StateFormatError, nest
from gear_fmu.mesh.element import MeshState
from gear_fmu.structure import StructureState

__all__ = ["bearing_state_arrays", "bearing_state_from_arrays", "laws_arrays",
           "laws_from_arrays", "restore_bearing_state", "structure_state_arrays",
           "structure_state_from_arrays"]

_MESH_FLOATS = ("delta", "load", "xi", "z")
_MESH_FLAGS = ("active", "inside")


# --- structure ---------------------------------------------------------------------------------
def _mesh_arrays(ms: MeshState) -> dict:
    out = {"force": ms.force, "stiffness": ms.stiffness,
           "total_load": np.float64(ms.total_load),
           "transmission_error": np.float64(ms.transmission_error)}
    out |= {name: getattr(ms, name) for name in _MESH_FLOATS + _MESH_FLAGS}
    return out | nest("extra", {k: np.float64(v) for k, v in ms.extra.items()})


def structure_state_arrays(state: StructureState) -> dict:
    """The entries of a structure state (module docstring)."""
    out = {"t": np.float64(state.t), "n_steps": np.int64(state.n_steps), "x": state.x,
           "v": state.v, "a": state.a}
    for m, ms in enumerate(state.mesh_states or ()):
        out |= nest(f"mesh/{m}", _mesh_arrays(ms))
    return out


def _sizes(structure) -> tuple[int | None, list | None]:
    """(n_dof, slices of each mesh) of a structure, None where unknown (no structure)."""
    if structure is None:
        return None, None
    return structure.x.size, [m.n_lines * m.n_slices for m in structure.meshes]


def _mesh_state(m: StateArrays, n: int | None) -> MeshState:
    values = {name: m.array(name, "float64", (n,)) for name in _MESH_FLOATS}
    n = values["delta"].size
    values |= {name: m.array(name, "bool", (n,)) for name in _MESH_FLAGS}
    extra = m.sub("extra")
    return MeshState(
        m.array("force", "float64", (12,)), m.array("stiffness", "float64", (12, 12)),
        values["active"], values["delta"], values["load"], values["inside"], values["xi"],
        values["z"], m.float("total_load"), m.float("transmission_error"),
        {name: extra.float(name) for name in extra.names()})


def structure_state_from_arrays(arrays: StateArrays, structure=None) -> StructureState:
    """The structure state of :func:`structure_state_arrays` entries, checked against
    ``structure`` (its number of DOFs, of meshes and of their slices) when given, else for
    consistency only (:class:`~fmu_src.state_codec.StateFormatError` otherwise)."""
    n_dof, slices = _sizes(structure)
    x = arrays.array("x", "float64", (n_dof,))
    v = arrays.array("v", "float64", x.shape)
    a = arrays.array("a", "float64", x.shape)
    t = arrays.float("t")
    n_steps = arrays.int("n_steps")
    if n_steps < 0:
        raise StateFormatError(f"{arrays.what}: n_steps = {n_steps}, must be >= 0")
    states = []
    if arrays.has_part("mesh"):
        meshes = arrays.sub("mesh")
        count = len(slices) if slices is not None else len(
            {name.split("/")[0] for name in meshes.names()})
        for m in range(count):
            states.append(_mesh_state(meshes.sub(str(m)), None if slices is None
                                      else slices[m]))
    if slices is not None and states and len(states) != len(slices):
        raise StateFormatError(f"{arrays.what}: {len(states)} mesh states for "
                               f"{len(slices)} meshes")
    return StructureState.of(t, n_steps, x, v, a, tuple(states) if states else None)


# --- bearing models ----------------------------------------------------------------------------
def bearing_state_arrays(model: BearingModel) -> dict:
    """The entries of a bearing model's state (module docstring); TypeError for a model with
    memory whose layout is not known here."""
    state = model.get_state()
    if state is None:
        return {}
    if isinstance(model, FiniteDifferenceBearing):
        p, have_p, active = state
        out = {"p": p, "have_p": np.bool_(have_p)}
        return out if active is None else out | {"active": np.asarray(active, dtype=np.bool_)}
    if isinstance(model, HybridBearing):
        record, active = state
        return nest("record", {name: record[0][name] for name in record.dtype.names}) | {
            "active": active}
    if isinstance(model, LinearisedBearing):
        law = state[1]
        out = nest("film", bearing_state_arrays(model.film))
        if law is not None:
            p0, f0, k, c, omega = law
            out |= nest("law", {"position0": np.array(p0, dtype=float),
                                "force0": np.array(f0, dtype=float),
                                "stiffness": np.array(k, dtype=float),
                                "damping": np.array(c, dtype=float), "omega": np.float64(omega)})
        return out
    raise TypeError(f"the state of a {type(model).__name__} has no array layout "
                    "(fmu_src.states)")


def _fd_state(model: FiniteDifferenceBearing, arrays: StateArrays):
    p_now = model.get_state()[0]
    p = arrays.array("p", "float64", p_now.shape)
    have_p = arrays.bool("have_p")
    active = None
    if arrays.has("active"):
        active = arrays.array("active", "bool", (model.n_theta * (model.n_xi - 1),))
    return p, have_p, active


def _hybrid_state(model: HybridBearing, arrays: StateArrays):
    record, active_now = model.get_state()
    rec = arrays.sub("record")
    for name in record.dtype.names:
        base, shape = record.dtype.fields[name][0].base, record.dtype.fields[name][0].shape
        kind = next((k for k in ("float64", "int64", "bool") if base == np.dtype(k)), None)
        if kind is None:  # pragma: no cover - a record field of a type a state cannot hold
            raise TypeError(f"hybrid state record field {name!r} has dtype {base}")
        record[0][name] = rec.array(name, kind, shape)
    return record, arrays.array("active", "bool", active_now.shape)


def bearing_state_from_arrays(model: BearingModel, arrays: StateArrays):
    """The model's own ``get_state`` form of :func:`bearing_state_arrays` entries, every one
    checked against ``model`` (a model built with the same parameters); nothing is applied."""
    if isinstance(model, FiniteDifferenceBearing):
        return _fd_state(model, arrays)
    if isinstance(model, HybridBearing):
        return _hybrid_state(model, arrays)
    if isinstance(model, LinearisedBearing):
        law = None
        if arrays.has_part("law"):
            m = arrays.sub("law")
            law = [m.array("position0", "float64", (2,)).tolist(),
                   m.array("force0", "float64", (2,)).tolist(),
                   m.array("stiffness", "float64", (2, 2)).tolist(),
                   m.array("damping", "float64", (2, 2)).tolist(), m.float("omega")]
        return bearing_state_from_arrays(model.film, arrays.sub("film")), law
    if model.get_state() is None:
        return None
    raise TypeError(f"the state of a {type(model).__name__} has no array layout "
                    "(fmu_src.states)")


def restore_bearing_state(model: BearingModel, arrays: StateArrays) -> None:
    """Set ``model`` to the state of :func:`bearing_state_arrays` entries, each checked
    against the model (a model built with the same parameters) before any is applied."""
    state = bearing_state_from_arrays(model, arrays)
    if state is not None:
        model.set_state(state)


# --- affine laws -------------------------------------------------------------------------------
def laws_arrays(laws: AffineLaws) -> dict:
    """The entries of a set of affine laws (module docstring)."""
    out = {"f0": laws.f0, "kb": laws.kb, "cb": laws.cb}
    if laws.states is not None:
        out["states"] = laws.states
    if laws.force_at is not None:
        out["force_at"] = laws.force_at
    return out


def laws_from_arrays(arrays: StateArrays, n_bearings: int) -> AffineLaws:
    """The affine laws of :func:`laws_arrays` entries, for ``n_bearings`` bearings."""
    nb = n_bearings
    states = arrays.array("states", "float64", (nb, 4)) if arrays.has("states") else None
    force_at = arrays.array("force_at", "float64", (nb, 2)) if arrays.has("force_at") else None
    return AffineLaws(arrays.array("f0", "float64", (nb, 2)),
                      arrays.array("kb", "float64", (nb, 2, 2)),
                      arrays.array("cb", "float64", (nb, 2, 2)), states, force_at)
