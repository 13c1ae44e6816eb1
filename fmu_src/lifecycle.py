"""The life cycle of the gear-shaft structure, one for both transports.

The in-process structure slave (:class:`orchestrator.coupling.inprocess.InProcessStructure`) and
the gear-shaft FMU (:class:`fmu_src.slaves.gear_shaft.GearShaftSlave`) drive a
:class:`gear_fmu.structure.Structure` through the same phases (:class:`Phase`), as the master's
static iteration and the FMI calls need them (paper Sec. 2.2.3 and 3.2):

* initialisation: static solutions for the bearing laws of each outer iteration
  (:meth:`StructureCycle.solve_static`); laws set after a solve make it stale;
* end of initialisation (:meth:`StructureCycle.exit_initialization`): a static solution if
  none was computed, then the modal damping built on the modes with the symmetric part of the
  laws' bearing stiffness;
* stepping (:meth:`StructureCycle.step`): Newmark steps from the structure's own time.

What a step outputs besides the journal states (each mesh's force and transmission error, u
and v of each gear's node) is computed once for both, :func:`step_output_row`, with the
arithmetic the coupled step records it with, so that both transports give the same bits.

>>> cycle = StructureCycle(lambda: None)
>>> cycle.phase
<Phase.NO_STATIC: 'no static solution'>
>>> cycle.laws_changed(); cycle.needs_static
True
"""

from __future__ import annotations

import enum

import numpy as np
from numba import njit

__all__ = ["Phase", "StructureCycle", "output_row", "step_output_row", "step_outputs",
           "transmission_error_terms"]


@njit(cache=True)
def step_output_row(te_idx, te_coef, gear_uv, totals, x, row):
    """What a step outputs into ``row`` (``2 n_meshes + 2 n_gears``): each mesh's total load
    ``totals`` [N], each mesh's transmission error ``r_b1 theta_1 + r_b2 theta_2`` [m] (the
    sum over its gear nodes' 12 DOFs in order: ``te_coef[m] . x[te_idx[m]]``,
    :func:`transmission_error_terms`), then u and v of each gear's node (``gear_uv``
    (n_gears, 2) their indices in ``x``) [m]. The coupled step
    (:func:`orchestrator.coupling.step.coupled_steps`) records its accepted steps with it, and
    the gear-shaft FMU outputs its state with it."""
    n_meshes = totals.size
    for m in range(n_meshes):
        row[m] = totals[m]
        acc = 0.0
        for j in range(12):
            acc += te_coef[m, j] * x[te_idx[m, j]]
        row[n_meshes + m] = acc
    for g in range(gear_uv.shape[0]):
        row[2 * n_meshes + 2 * g] = x[gear_uv[g, 0]]
        row[2 * n_meshes + 2 * g + 1] = x[gear_uv[g, 1]]


@njit(cache=True)
def output_row(journal_idx, nc, te_idx, te_coef, gear_uv, totals, x, v, row, first):
    """Everything a gear-shaft FMU outputs, in one call: the journal states into
    ``row[:journal_idx.size]`` (``journal_idx`` their indices in ``[x[:nc], v[:nc]]``: u, v,
    udot, vdot per bearing [m, m/s]) and :func:`step_output_row` into ``row[first:]``; the
    entries between (the shaft speeds) are left as they are."""
    for i in range(journal_idx.size):
        j = journal_idx[i]
        row[i] = x[j] if j < nc else v[j - nc]
    step_output_row(te_idx, te_coef, gear_uv, totals, x, row[first:])


def transmission_error_terms(structure) -> tuple[np.ndarray, np.ndarray]:
    """``(te_idx, te_coef)`` (n_meshes, 12) of a :class:`gear_fmu.structure.Structure`: where
    each mesh's gear-node DOFs sit in its state vector and their coefficients in the
    transmission error (the compiled loop's mesh arrays, ``[12]`` and ``[13]``:
    :meth:`gear_fmu.step.contact_loop.MeshWork.arrays`)."""
    meshes = structure._mesh_tuple
    return (np.array([m[12] for m in meshes], dtype=np.int64).reshape(-1, 12),
            np.array([m[13] for m in meshes], dtype=np.float64).reshape(-1, 12))


def step_outputs(structure, terms=None) -> np.ndarray:
    """:func:`step_output_row` of a structure's current state (``terms``: its
    :func:`transmission_error_terms`, computed when not given)."""
    st = structure
    te_idx, te_coef = transmission_error_terms(st) if terms is None else terms
    row = np.empty(2 * te_idx.shape[0] + 2 * st._gear_uv.shape[0])
    step_output_row(te_idx, te_coef, st._gear_uv, st._totals, st.x, row)
    return row


class Phase(enum.Enum):
    """Where the structure is in its life cycle."""

    NO_STATIC = "no static solution"
    STATIC = "static solution of the current laws"
    STALE = "static solution of earlier laws"
    STEPPING = "stepping"


class StructureCycle:
    """The phase of one structure and the transitions between phases.

    Parameters
    ----------
    build : callable
        ``build() -> Structure``: the structure, built when first needed (the property
        ``structure``) and again after :meth:`reset`.
    """

    def __init__(self, build):
        self._build = build
        self.built = None  # the structure once built
        self.phase = Phase.NO_STATIC
        #: the symmetric bearing stiffness (4, 2, 2) [N/m] the modal damping was built with
        self.damping_kb = None

    @property
    def structure(self):
        """The structure (:class:`gear_fmu.structure.Structure`), built on first use."""
        if self.built is None:
            self.built = self._build()
        return self.built

    @property
    def stepping(self) -> bool:
        return self.phase is Phase.STEPPING

    @property
    def needs_static(self) -> bool:
        """In initialisation, without a static solution of the current laws."""
        return self.phase in (Phase.NO_STATIC, Phase.STALE)

    @property
    def has_static(self) -> bool:
        """The structure holds a static solution (of the current laws or earlier ones)."""
        return self.phase in (Phase.STATIC, Phase.STALE)

    def reset(self) -> None:
        """A new structure (other parameters): built again when needed, no static solution."""
        self.built = None
        self.damping_kb = None
        if not self.stepping:
            self.phase = Phase.NO_STATIC

    def laws_changed(self) -> None:
        """New bearing laws: in initialisation the static solution is stale (when stepping they
        act at the next step only)."""
        if self.phase is Phase.STATIC:
            self.phase = Phase.STALE

    def solve_static(self, f0, kb, cb):
        """Static solution for the laws ``f0, kb, cb`` (Eq. 17); the structure's report."""
        if self.stepping:
            raise RuntimeError("a static solution after the end of initialisation")
        info = self.structure.static(f0, kb, cb)
        self.phase = Phase.STATIC
        return info

    def exit_initialization(self, f0, kb, cb):
        """End of initialisation: a static solution if none was computed (its report is
        returned, else None), then the modal damping on the modes with the symmetric part of
        ``kb``; stepping from then on."""
        info = self.solve_static(f0, kb, cb) if self.phase is Phase.NO_STATIC else None
        self.set_damping(0.5 * (kb + np.transpose(kb, (0, 2, 1))))
        self.phase = Phase.STEPPING
        return info

    def set_damping(self, kb) -> None:
        """Modal damping on the modes with bearing stiffness ``kb`` (kept: states share it)."""
        self.structure.set_damping_reference(kb)
        self.damping_kb = kb.copy()  # never changed in place: saved states share it

    def step(self, t: float, dt: float, f0, kb, cb):
        """One Newmark step from ``t`` [s] (the structure's time) to ``t + dt``; the report."""
        return self.check_step(t, dt).step(dt, f0, kb, cb)

    def check_step(self, t: float, dt: float):
        """The structure, if a step from ``t`` [s] may start (stepping, at the structure's
        time); the error otherwise."""
        if not self.stepping:
            raise RuntimeError("a step before the end of initialisation")
        st = self.structure
        if abs(t - st.t) > 1e-9 * max(dt, abs(t)):
            raise ValueError(f"a step from t = {t!r} s but the structure is at t = {st.t!r} s")
        return st
