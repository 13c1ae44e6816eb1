"""In-process slaves: the physics objects behind the master's interface, no FMI layer.

* :class:`InProcessStructure`: a :class:`gear_fmu.structure.Structure` as a
  :class:`~orchestrator.coupling.master.StructureSlave`.
* :class:`ModelBearings`: bearing models (:mod:`bearing_fmu`) as a
  :class:`~orchestrator.coupling.master.BearingSet`, converting between their local frames and the
  global (s, t) frame.
"""

from __future__ import annotations

import numpy as np

from bearing_fmu.affine import AffineLaws
from bearing_fmu.base import BearingError, BearingModel
from bearing_fmu.frames import LocalFrame
from bearing_fmu.hybrid.model import HybridSet
from bearing_fmu.short_bearing import ShortSet
from fmu_src.lifecycle import StructureCycle
from fmu_src.state_codec import StateArrays, nest
from fmu_src.states import (
    bearing_state_arrays,
    bearing_state_from_arrays,
    structure_state_arrays,
    structure_state_from_arrays,
)
from gear_fmu.modal.analyses import support_loads
from gear_fmu.structure import Structure
from orchestrator.coupling.master import BearingSet, StructureSlave

__all__ = ["InProcessStructure", "ModelBearings"]


class InProcessStructure(StructureSlave):
    """The gear-shaft structure driven directly (what the gear-shaft FMU does through FMI),
    through the life cycle both transports share (:class:`fmu_src.lifecycle.StructureCycle`).

    Parameters
    ----------
    structure : gear_fmu.structure.Structure
    """

    n_bearings = Structure.n_bearings

    def __init__(self, structure: Structure):
        self.structure = structure
        self.cycle = StructureCycle(lambda: structure)
        self._laws: AffineLaws | None = None

    @property
    def physics(self) -> Structure:
        return self.structure

    def _require_laws(self) -> AffineLaws:
        if self._laws is None:
            raise RuntimeError("set_bearing_laws() before a static solution or a step")
        return self._laws

    def get_state(self):
        return self.structure.get_state()

    def set_state(self, state) -> None:
        self.structure.set_state(state)

    def set_bearing_laws(self, laws: AffineLaws) -> None:
        self._laws = laws
        self.cycle.laws_changed()

    def do_step(self, t: float, dt: float) -> None:
        laws = self._require_laws()
        self.cycle.step(t, dt, laws.f0, laws.kb, laws.cb)

    def solve_static(self) -> None:
        laws = self._require_laws()
        self.cycle.solve_static(laws.f0, laws.kb, laws.cb)

    def exit_initialization(self) -> None:
        laws = self._require_laws()
        self.cycle.exit_initialization(laws.f0, laws.kb, laws.cb)

    def checkpoint(self) -> dict:
        return structure_state_arrays(self.structure.get_state())

    def restore(self, checkpoint: StateArrays) -> None:
        self.structure.set_state(structure_state_from_arrays(checkpoint, self.structure))

    def journal_states(self) -> np.ndarray:
        return self.structure.journal_states()

    def support_loads(self) -> np.ndarray:
        return support_loads(self.structure)

    def mesh_force(self) -> float:
        return self.structure.mesh_force()

    def transmission_error(self) -> float:
        return self.structure.transmission_error()

    def gear_displacements(self) -> np.ndarray:
        return self.structure.gear_displacements()[:, :2]


class ModelBearings(BearingSet):
    """Bearing models evaluated directly, converted between local and global frames.

    Parameters
    ----------
    models : sequence of BearingModel
        One per bearing node.
    frames : sequence of LocalFrame
        Local frame of each bearing in the global (s, t) plane.
    omegas : sequence of float
        Shaft speed magnitude at each bearing [rad/s].
    """

    def __init__(self, models, frames, omegas):
        if not (len(models) == len(frames) == len(omegas)):
            raise ValueError("models, frames and omegas must have one entry per bearing")
        self.frames = [f if isinstance(f, LocalFrame) else LocalFrame(*f) for f in frames]
        self.omegas = [float(w) for w in omegas]
        for w in self.omegas:
            if not (np.isfinite(w) and w > 0.0):
                raise ValueError(f"shaft speed {w!r} rad/s must be finite and > 0")
        for m in models:
            if not isinstance(m, BearingModel):
                raise TypeError(f"{m!r} is not a BearingModel")
        self.models = list(models)
        self.clearances = np.array([m.bearing.clearance for m in self.models])
        self._q = np.array([f.q for f in self.frames])
        self._states = None  # global journal states of the last evaluation
        self.evaluations = 0
        # hybrid bearings of one n, or short bearings: one compiled call for the set (the same
        # numbers)
        self._set = next((kind(self.models, self._q, self.omegas)
                          for kind in (HybridSet, ShortSet) if kind.fits(self.models)), None)
        self._affine = None  # (the laws, their arrays) of affine_laws()

    def evaluate(self, states):
        nb = len(self.models)
        states = np.ascontiguousarray(states, dtype=float)  # as the set's compiled call takes it
        self._states = states.copy()
        out = np.empty((nb, 5, 2))
        b = 0
        try:
            if self._set is not None:
                self._set.evaluate_global(states, out)
            else:
                for b in range(nb):
                    self.models[b].evaluate_global(self._q[b], states[b], self.omegas[b],
                                                   out[b])
        except BearingError as exc:
            self._annotate(exc, b, states)
            raise
        self.evaluations += nb
        return out[:, 0], out[:, 1:3], out[:, 3:5]

    @staticmethod
    def _annotate(exc, b, states) -> None:
        """Which bearing failed, at which state [m, m/s]: what the run reports."""
        b = getattr(exc, "bearing_index", b)
        exc.bearing, exc.state, exc.reason = b + 1, states[b].copy(), str(exc)

    @property
    def hybrid_set(self) -> HybridSet | None:
        """The compiled call of a set of hybrid bearings of one n, else None."""
        return self._set if isinstance(self._set, HybridSet) else None

    @property
    def compiled_set(self) -> HybridSet | ShortSet | None:
        """The compiled call of the set (:attr:`hybrid_set`, or a
        :class:`bearing_fmu.short_bearing.ShortSet`), else
        None: what a compiled caller evaluates the bearings with
        (:mod:`orchestrator.coupling.fused`)."""
        return self._set

    def affine_laws(self):
        """``(q, f0, kb, cb)`` stacked over the bearings ((nb, 2, 2), (nb, 2), (nb, 2, 2) x 2:
        the global-to-local rotations and the local laws) when every bearing's law is affine
        now (:meth:`bearing_fmu.base.BearingModel.affine_law`: the ``linear`` model after its
        freeze at X0, the ``lumped`` one), for a compiled caller
        (``bearing_fmu.affine.affine_set_global``); else None."""
        laws = tuple(m.affine_law(w) for m, w in zip(self.models, self.omegas, strict=True))
        if any(law is None for law in laws):
            return None
        if self._affine is None or any(a is not b for a, b in zip(self._affine[0], laws,
                                                                    strict=True)):
            self._affine = (laws, (self._q, np.array([law.f0 for law in laws]),
                                   np.array([law.kb for law in laws]),
                                   np.array([law.cb for law in laws])))
        return self._affine[1]

    def record_states(self, states) -> None:
        """The journal states (nb, 4) [m, m/s] a compiled caller evaluated the set at last."""
        self._states = np.array(states, dtype=float)

    def raise_set_failure(self, b, status, states) -> None:
        """The error :meth:`evaluate` raises when the compiled set's bearing ``b`` (0-based)
        returned ``status`` at ``states`` (nb, 4) (a compiled caller's failure)."""
        self.record_states(states)
        try:
            self._set.raise_status(b, status, states)
        except BearingError as exc:
            self._annotate(exc, b, states)
            raise

    def checkpoint(self) -> dict:
        """Each model's state (:func:`fmu_src.states.bearing_state_arrays`) under its index."""
        out = {}
        for b, model in enumerate(self.models):
            out |= nest(str(b), bearing_state_arrays(model))
        return out

    def restore(self, checkpoint: StateArrays) -> None:
        states = [bearing_state_from_arrays(model, checkpoint.sub(str(b)))
                  for b, model in enumerate(self.models)]  # all checked before any is set
        for model, state in zip(self.models, states, strict=True):
            if state is not None:
                model.set_state(state)

    def exit_initialization(self) -> None:
        if self._states is None:
            raise RuntimeError("exit_initialization before any evaluation (no static state)")
        for model, frame, state, om in zip(self.models, self.frames, self._states, self.omegas,
                                           strict=True):
            x, y = frame.to_local(state[:2])
            model.end_initialization(float(x), float(y), om)
