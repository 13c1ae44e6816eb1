"""In-process slaves: the physics objects behind the master's interface, no FMI layer.

* :class:`InProcessStructure`: a :class:`gear_fmu.structure.Structure` as a
  :class:`~orchestrator.coupling.master.StructureSlave`.
* :class:`ModelBearings`: bearing models (:mod:`bearing_fmu`), each bearing its own, as a
  :class:`~orchestrator.coupling.master.BearingSet`, converting between their local frames and
  the global (s, t) frame; grouped by kind for the compiled coupled step (hybrid bearings of
  one n share one call, short bearings another, affine laws a third, any other model is
  called back in Python).
"""

from __future__ import annotations

import numpy as np

from bearing_fmu.affine import AffineLaws, affine_set_arguments
from bearing_fmu.base import BearingError, BearingModel
from bearing_fmu.frames import LocalFrame
from bearing_fmu.hybrid.model import HybridBearing, HybridSet
from bearing_fmu.short_bearing import ShortBearing, ShortSet
from fmu_src.lifecycle import StructureCycle, step_outputs, transmission_error_terms
from fmu_src.state_codec import StateArrays, nest
from fmu_src.states import (
    bearing_state_arrays,
    bearing_state_from_arrays,
    structure_state_arrays,
    structure_state_from_arrays,
)
from gear_fmu.modal.analyses import support_loads
from gear_fmu.structure import Structure
from orchestrator.coupling.master import BearingSet, PythonGroup, StructureSlave

__all__ = ["InProcessStructure", "ModelBearings"]


class InProcessStructure(StructureSlave):
    """The gear-shaft structure driven directly (what the gear-shaft FMU does through FMI),
    through the life cycle both transports share (:class:`fmu_src.lifecycle.StructureCycle`).

    Parameters
    ----------
    structure : gear_fmu.structure.Structure
    """

    def __init__(self, structure: Structure):
        self.structure = structure
        self.cycle = StructureCycle(lambda: structure)
        self._laws: AffineLaws | None = None
        self.n_bearings = structure.nb
        self.n_meshes = len(structure.meshes)
        self.n_gears = len(structure.layout.gears)
        self._plan = None  # the plan of the last compiled block (its failure's details)
        self._te_terms = None  # transmission_error_terms of the structure

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

    def bearing_speeds_after(self, dt: float):
        return self.structure.bearing_speeds_at(self.structure.t + dt)

    def compiled_block(self, t: float, dt: float, n: int, time_of):
        """The structure's planned steps (:meth:`gear_fmu.structure.Structure.steps_plan`) as
        :func:`orchestrator.coupling.step.coupled_steps` takes them: ``(head, state, tail,
        work, (gear_uv, totals, lengths, te_idx, te_coef))``, ``gear_uv`` (n_gears, 2) the
        condensed indices of each gear node's u, v, ``totals``, ``lengths`` (n_meshes,)
        receiving the meshes' total loads [N] and contact lengths [m] of each accepted step,
        ``te_idx``, ``te_coef`` the transmission errors' terms
        (:func:`fmu_src.lifecycle.transmission_error_terms`)."""
        st = self.cycle.check_step(t, dt)
        plan = st.steps_plan(dt, n)
        self._plan = plan
        totals, lengths = st.mesh_forces(), np.zeros(self.n_meshes)
        args = (plan.head, plan.state, plan.tail, plan.work,
                (st._gear_uv, totals, lengths, *self._terms()))

        def finish(count: int) -> None:
            st.end_steps(plan, count, totals, lengths)

        return args, len(plan.ends), finish

    def raise_compiled_failure(self, k, code, d1, d2, d3, t, dt) -> None:
        """The structure's error of the block's step ``k``: the step kernel's status ``d1``
        at sub-step ``d2`` after ``d3`` passes."""
        plan = self._plan
        residuals = plan.work[4]
        self.structure.raise_failed_step(d1, d3, residuals, plan.ends[k][d2])

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

    def _terms(self):
        """The structure's :func:`fmu_src.lifecycle.transmission_error_terms` (kept)."""
        if self._te_terms is None:
            self._te_terms = transmission_error_terms(self.structure)
        return self._te_terms

    def step_outputs(self):
        row = step_outputs(self.structure, self._terms())
        n = self.n_meshes
        return row[:n], row[n:2 * n], row[2 * n:].reshape(-1, 2)


def _kind(model) -> tuple:
    """The group a model's bearing joins (module docstring): hybrid bearings of one n, short
    bearings, or the others (affine once their law is, else called back in Python)."""
    if type(model) is HybridBearing:
        return ("hybrid", model.n)
    if type(model) is ShortBearing:
        return ("short",)
    return ("other",)


class ModelBearings(BearingSet):
    """Bearing models evaluated directly, converted between local and global frames.

    Parameters
    ----------
    models : sequence of BearingModel
        One per bearing (the layout's order), of any registered model each.
    frames : sequence of LocalFrame
        Local frame of each bearing in the global (s, t) plane.
    omegas : sequence of float
        Shaft speed magnitude at each bearing [rad/s].
    names : sequence of str, optional
        The bearings' names (messages); default "1", "2", ...
    """

    def __init__(self, models, frames, omegas, names=None):
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
        self.names = [str(i + 1) for i in range(len(self.models))] if names is None else [
            str(n) for n in names]
        self.clearances = np.array([m.bearing.clearance for m in self.models])
        self._q = np.array([f.q for f in self.frames]).reshape(-1, 2, 2)
        self._states = None  # global journal states of the last evaluation
        self.evaluations = 0
        kinds: dict[tuple, list[int]] = {}
        for b, m in enumerate(self.models):
            kinds.setdefault(_kind(m), []).append(b)
        #: (kind, bearing indices, the compiled set or None) in the order kinds first appear
        self._groups = []
        for kind, index in kinds.items():
            idx = np.array(index, dtype=np.int64)
            sub = [self.models[b] for b in index]
            args = (sub, self._q[idx], [self.omegas[b] for b in index])
            compiled = HybridSet(*args) if kind[0] == "hybrid" else (
                ShortSet(*args) if kind[0] == "short" else None)
            self._groups.append((kind, idx, compiled))
        self._python = None  # the PythonGroup of the models without a compiled form
        self._affine = None  # (the laws, their group) of the affine models

    @property
    def count(self) -> int:
        return len(self.models)

    @property
    def hybrid_sets(self) -> list[HybridSet]:
        """The compiled calls of the hybrid bearings (one per n)."""
        return [c for _, _, c in self._groups if isinstance(c, HybridSet)]

    def _evaluate_models(self, index, states, out) -> None:
        """Bearings ``index`` one by one at their global states (k, 4) into ``out`` (k, 5, 2);
        a failure carries the set's index in ``bearing_index``."""
        for g, b in enumerate(index):
            try:
                self.models[b].evaluate_global(self._q[b], states[g], self.omegas[b], out[g])
            except BearingError as exc:
                exc.bearing_index = int(b)
                raise

    def evaluate(self, states):
        states = np.ascontiguousarray(states, dtype=float)  # as the compiled calls take it
        self._states = states.copy()
        out = np.empty((self.count, 5, 2))
        for _, idx, compiled in self._groups:
            sub, rows = states[idx], np.empty((idx.size, 5, 2))
            try:
                if compiled is not None:
                    try:
                        compiled.evaluate_global(sub, rows)
                    except BearingError as exc:
                        exc.bearing_index = int(idx[getattr(exc, "bearing_index", 0)])
                        raise
                else:
                    self._evaluate_models(idx, sub, rows)
            except BearingError as exc:
                self._annotate(exc, exc.bearing_index, states)
                raise
            out[idx] = rows
        self.evaluations += self.count
        return out[:, 0], out[:, 1:3], out[:, 3:5]

    def set_speeds(self, omegas) -> None:
        """The shaft speed at each bearing [rad/s] from the next evaluation on (a run-up): the
        compiled sets' arrays in place, the others' at their next call."""
        self.omegas = [float(w) for w in omegas]
        for _, idx, compiled in self._groups:
            if compiled is not None:
                compiled.set_speeds([self.omegas[b] for b in idx])

    def _annotate(self, exc, b, states) -> None:
        """Which bearing failed, at which state [m, m/s]: what the run reports."""
        exc.bearing_index = int(b)
        exc.bearing, exc.state, exc.reason = self.names[b], states[b].copy(), str(exc)

    def compiled_groups(self) -> tuple:
        groups = []
        others = []
        for _, idx, compiled in self._groups:
            if compiled is not None:
                groups.append((compiled.kernel_arguments(), idx))
            else:
                others.extend(int(b) for b in idx)
        affine = [b for b in others
                  if self.models[b].affine_law(self.omegas[b]) is not None]
        if affine:
            groups.append((self._affine_arguments(affine), np.array(affine, dtype=np.int64)))
        python = [b for b in others if b not in affine]
        if python:
            if self._python is None or self._python.indices.tolist() != python:
                if self._python is not None:
                    self._python.close()
                self._python = PythonGroup(self._evaluate_models, python)
            groups.append(self._python.arguments())
        return tuple(groups)

    def _affine_arguments(self, index) -> tuple:
        """``(q, f0, kb, cb)`` of the affine laws of bearings ``index``, stacked (local frame,
        :meth:`bearing_fmu.base.BearingModel.affine_law`), kept while the laws are the
        same objects."""
        laws = tuple(self.models[b].affine_law(self.omegas[b]) for b in index)
        if self._affine is None or any(a is not b for a, b in zip(self._affine[0], laws,
                                                                    strict=False)):
            self._affine = (laws, affine_set_arguments(self._q[index], laws))
        return self._affine[1]

    def raise_failure(self, b, status, states) -> None:
        self.record_states(states)
        for _, idx, compiled in self._groups:
            where = np.flatnonzero(idx == b)
            if compiled is not None and where.size:
                try:
                    compiled.raise_status(int(where[0]), status, states[idx])
                except BearingError as exc:
                    self._annotate(exc, b, states)
                    raise
        if self._python is not None and self._python.error is not None:
            exc, self._python.error = self._python.error, None
            self._annotate(exc, b, states)
            raise exc
        raise RuntimeError(f"bearing {self.names[b]}: status {status} without an error")

    def record_states(self, states) -> None:
        self._states = np.array(states, dtype=float)

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

    def close(self) -> None:
        if self._python is not None:
            self._python.close()
            self._python = None
