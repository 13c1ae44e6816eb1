"""pythonfmu slave of the gear-shaft FMU: the contract's variables around one ``Structure``.

Nothing physical happens here: the slave builds :class:`gear_fmu.structure.Structure` from its
case (``resources/case.toml`` with the FMU parameters' values, through :mod:`fmu_src.case` and
:mod:`fmu_src.description`, the system description shared with the in-process runs), keeps the
law inputs (14 per bearing, layout: :func:`fmu_src.contract.unpack_law_arrays`: each bearing
FMU's outputs) and maps the FMI calls onto the structure through the life cycle the in-process
transport shares (:class:`fmu_src.lifecycle.StructureCycle`, its phase a
:class:`fmu_src.lifecycle.Phase`). Its variables are those of its carried case's gear train
(:func:`fmu_src.contract.gear_variables`: one group of ports per bearing, named after it, the
outputs of every mesh and gear): the numbers of bearings, meshes and gears, and every size
below, come from that case.

* initialisation mode: outputs are the static solution for the current laws, solved in the
  getter when an input changed since the last solve (the master iterates X0 this way);
* ``exitInitializationMode``: static solution if none was computed yet, then
  ``set_damping_reference`` with the symmetric part of the current Kb laws;
* ``doStep(t, dt)``: one ``Structure.step`` from t (must be the structure's time) to t + dt;
* ``get/setFMUstate``: structure state, parameters, laws, outputs and the bearing stiffness
  the modal damping was built with (exact rollback, and a restart in another instance or
  process); serialised as numeric arrays (:mod:`fmu_src.state_codec`, never a pickle: bytes
  that are not such a state are refused with fmi2Error).

A refused value (out of its bounds, non-finite) is reported by the set call (fmi2Error); a
failed solution or a case whose fields do not fit together by the read of the outputs
(fmi2Error) or the doStep (fmi2Discard), the reason in the log: a Python exception escaping a
pythonfmu callback would be fatal for the instance and its host. A step that cannot be computed
(a Newton iteration that does not converge, a step longer than :data:`MAX_STEP_MESH_PERIODS`
mesh periods) leaves the structure at no computed state: its outputs then read fmi2Error and
further steps are refused until ``fmi2SetFMUstate`` restores a saved state.

The slave keeps the law inputs (14 nb for nb bearings) and the journal outputs (4 nb) in one
float64 array, the *I/O buffer* (:data:`IO_LAYOUT`: the laws, the journals, then the flag
"laws armed" and the flag "journals valid", :func:`io_size` values), and answers
``_fmi_native_io`` with its address, its size and the value references of both groups, whose
counts the library checks against that layout. The patched FMU library
(``fmu_src/native/patches/0012-native-structure-io.patch``) then serves the master's two calls
around each doStep itself: fmi2SetReal of the law inputs (finite values) while the slave is
stepping (the laws act at the next doStep only), and fmi2GetReal of the journal outputs while
the buffer holds those of the current state (a doStep computes them). Neither enters Python;
every other call does, and reads and writes the same buffer.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from pythonfmu.default_experiment import DefaultExperiment

from fmu_src.contract import (
    GEAR_DEFAULT_CASE,
    LAWS_PER_BEARING,
    STATE_NAMES,
    ValueRefused,
    gear_variables,
    journal_output_names,
    law_input_names,
    speed_output_names,
    step_output_names,
    support_load_names,
    unpack_law_arrays,
)
from fmu_src.lifecycle import Phase, StructureCycle, output_row, transmission_error_terms
from fmu_src.slaves.support import (
    FMI_ERROR,
    ContractSlave,
    case_parameter,
    overrides_from_arrays,
    overrides_to_arrays,
)
from fmu_src.state_codec import StateArrays, StateFormatError, nest
from fmu_src.states import structure_state_arrays, structure_state_from_arrays

__all__ = ["CASE_RESOURCE", "IO_LAYOUT", "GearShaftSlave", "io_size"]

#: the case an FMU carries, in its resources
CASE_RESOURCE = "case.toml"

#: the I/O buffer's layout (module docstring): for nb bearings, the law inputs at 0 ... 14 nb - 1
#: (order of fmu_src.contract.law_input_names), the journal outputs at 14 nb ... 18 nb - 1
#: (order of fmu_src.contract.journal_output_names), then 1.0 at 18 nb while stepping (the
#: library may write the laws) and 1.0 at 18 nb + 1 while the journals are the outputs of the
#: current state (no failure). The library serves the calls natively only for a buffer of the
#: layout it knows: the patch repeats it, and a change of it changes this name there and here
IO_LAYOUT = "gsb-structure-io-2"
_JOURNALS_PER_BEARING = len(STATE_NAMES)
_FLAGS = ("dirty", "failed")


def io_size(n_bearings: int) -> int:
    """The length of the I/O buffer of a train of ``n_bearings`` bearings (:data:`IO_LAYOUT`)."""
    return (LAWS_PER_BEARING + _JOURNALS_PER_BEARING) * n_bearings + 2
#: the kind tag of this slave's serialised states (fmu_src.state_codec)
STATE_KIND = "gsb.gear_shaft_fmu_state"
#: the longest step doStep takes, in mesh periods: a longer one resolves nothing of the mesh
#: dynamics, and with contact location (``simulation.locate_contact``) it is cut at every
#: contact event it spans (a step of 1e6 s would be cut ~1e10 times and never end)
MAX_STEP_MESH_PERIODS = 100


class GearShaftSlave(ContractSlave):
    """Gear-shaft structure as an FMI 2.0 co-simulation slave (module docstring)."""

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.description = (
            "Gear-shaft structure of a parallel-axis gear train (Timoshenko shafts, distributed "
            "gear meshes, Newmark/Newton/contact step) driven by the outputs of one bearing FMU "
            "per bearing; global frame, SI units (Baguet & Jacquenot 2010)."
        )
        from fmu_src.description import time_step

        self._base = self._base_case()
        step = time_step(self._base)
        #: two mesh periods of the carried case at its time step (``fmpy simulate`` defaults)
        self.default_experiment = DefaultExperiment(start_time=0.0, stop_time=64 * step,
                                                    step_size=step)
        base = self._base
        variables = gear_variables(base)
        starts = {v.name: v.start for v in variables}
        # the names of the train's ports (fmu_src.contract), in the order of the buffers
        self._law_names = law_input_names(base)
        self._journal_names = journal_output_names(base)
        self._output_names = [*self._journal_names, *speed_output_names(base),
                              *step_output_names(base)]
        self._support_names = support_load_names(base)
        nb = len(self._journal_names) // _JOURNALS_PER_BEARING
        self._nb = nb
        self._nan_outputs = [math.nan] * len(self._output_names)
        self._overrides: dict = {}  # case field -> value set through a parameter
        self._io = np.zeros(io_size(nb))  # the I/O buffer (module docstring)
        n_laws, n_journals = LAWS_PER_BEARING * nb, _JOURNALS_PER_BEARING * nb
        self._io_journals = slice(n_laws, n_laws + n_journals)
        self._io_armed, self._io_valid = n_laws + n_journals, n_laws + n_journals + 1
        self._laws = self._io[:n_laws]  # never rebound: setters hold it
        self._laws[:] = [float(starts[n]) for n in self._law_names]
        self._outputs = list(self._nan_outputs)
        self._row = None  # output_row's constant arguments and its row, speeds filled
        self._iterations = 0
        self._support: list | None = None
        self._cycle = StructureCycle(self._build_structure)  # phases shared with in-process
        self._start_time = 0.0
        self._dirty_outputs = True  # outputs must be recomputed from the structure
        self._failed = False  # the last output computation failed
        self._error: str | None = None  # a failure that forbids stepping (build, initialisation)
        self._register_all(variables)

    def _base_case(self):
        from fmu_src.case import load_case, shipped_case

        if self.resources is not None and (Path(self.resources) / CASE_RESOURCE).is_file():
            return load_case(Path(self.resources) / CASE_RESOURCE)
        return shipped_case(GEAR_DEFAULT_CASE.removesuffix(".toml"))

    # --- FMI plumbing ------------------------------------------------------------------------
    def _register_all(self, variables) -> None:
        index = {name: i for i, name in enumerate(self._law_names)}
        out_index = {name: i for i, name in enumerate(self._output_names)}
        sup_index = {name: i for i, name in enumerate(self._support_names)}
        fixed = {v.name: v.start for v in variables if v.name.startswith(("rotation_sign_",
                                                                          "frame_angle_"))}
        for v in variables:
            if v.causality == "parameter":
                self.register_contract_variable(
                    v, *case_parameter(self, v.name, self._reset_structure))
            elif v.name in index:
                i = index[v.name]
                self.register_contract_variable(v, self._law_getter(i), self._law_setter(i))
            elif v.name in out_index:
                self.register_contract_variable(v, self._output_getter(out_index[v.name]))
            elif v.name == "iterations":
                self.register_contract_variable(v, self._get_iterations)
            elif v.name in sup_index:
                self.register_contract_variable(v, self._support_getter(sup_index[v.name]))
            elif v.name in fixed:
                self.register_contract_variable(v, lambda value=fixed[v.name]: value)
            else:  # pragma: no cover - the contract and this slave disagree
                raise RuntimeError(f"gear-shaft slave has no handler for variable {v.name!r}")
        vr = {v.name: v.value_reference for v in self.vars.values()}
        self._law_vrs = [vr[n] for n in self._law_names]
        self._journal_vrs = [vr[n] for n in self._journal_names]

    def _fmi_native_io(self):
        """What the patched library needs to serve the law inputs and the journal outputs
        itself (module docstring): ``(layout, buffer address, buffer size, law value
        references, journal value references)``, the library checking the counts against
        the layout. Called once per instance; the address holds while the slave lives (the
        buffer is never replaced)."""
        return (IO_LAYOUT, self._io.ctypes.data, self._io.size, tuple(self._law_vrs),
                tuple(self._journal_vrs))

    @property
    def _dirty(self) -> bool:
        """The outputs must be recomputed from the structure (then the buffer's journal outputs
        are not those of the current state either)."""
        return self._dirty_outputs

    @_dirty.setter
    def _dirty(self, dirty: bool) -> None:
        self._dirty_outputs = dirty
        if dirty:
            self._io[self._io_valid] = 0.0

    def _arm_laws(self) -> None:
        """Let the library write the laws while stepping: they then act at the next doStep
        only (set_real), so a set changes nothing else. Called after every phase change."""
        self._io[self._io_armed] = 1.0 if self._cycle.stepping else 0.0

    def _take_outputs(self, outputs: list) -> None:
        """``outputs`` (finite) as the current state's, the journal ones in the buffer too."""
        self._outputs = outputs
        self._failed = False
        self._dirty = False
        self._io[self._io_journals] = outputs[:len(self._journal_names)]
        self._io[self._io_valid] = 1.0

    def _fail_outputs(self) -> None:
        """No outputs: they read NaN with fmi2Error until the structure has a state again."""
        self._outputs = list(self._nan_outputs)
        self._failed = True
        self._dirty = False
        self._io[self._io_valid] = 0.0

    # The master sets all the law inputs and reads all the journal states in one call each:
    # served without the per-variable loop (same checks and effect, several times cheaper).
    def set_real(self, vrs, values):
        if vrs == self._law_vrs:
            if not all(map(math.isfinite, values)):
                bad = next(n for n, x in zip(self._law_names, values, strict=True)
                           if not math.isfinite(x))
                return self.refuse(ValueRefused(
                    f"bearing laws refused: {bad} is not a finite number (no input applied)"))
            laws = self._laws
            if self._cycle.stepping:
                laws[:] = values
            elif laws.tolist() != values:
                laws[:] = values
                self._cycle.laws_changed()
                self._dirty = True
            return None
        return super().set_real(vrs, values)

    def get_real(self, vrs):
        if vrs == self._journal_vrs:
            if self._dirty:
                self._refresh()
            if self._failed:
                self._read_status = 3
            return self._with_status(self._outputs[:len(self._journal_vrs)])
        return super().get_real(vrs)

    def _reset_structure(self) -> None:
        self._cycle.reset()
        self._arm_laws()
        self._support = None
        self._row = None
        self._dirty = True
        self._error = None

    def _law_getter(self, i):
        laws = self._laws
        return lambda: float(laws[i])

    def _law_setter(self, i):
        laws = self._laws

        def set_(value):
            if laws[i] != value:
                laws[i] = value
                if not self._cycle.stepping:  # step mode: the laws act at the next doStep only
                    self._cycle.laws_changed()
                    self._dirty = True
        return set_

    def _output_getter(self, k):
        def get():
            if self._dirty:
                self._refresh()
            if self._failed:
                self._read_status = 3
            return self._outputs[k]
        return get

    def _get_iterations(self):
        if self._dirty:
            self._refresh()
        return self._iterations

    def _support_getter(self, k):
        def get():
            if self._support is None:
                self._compute_support()
            if any(math.isnan(x) for x in self._support):
                self._read_status = 3
            return self._support[k]
        return get

    # --- physics ------------------------------------------------------------------------------
    def case(self):
        """The case the FMU simulates: its carried case with the parameters' values."""
        return self._base.with_overrides(self._overrides) if self._overrides else self._base

    def _build_structure(self):
        from fmu_src.description import bearing_speeds, structure

        case = self.case()
        st = structure(case)
        self._speeds = bearing_speeds(case)
        st.t = self._start_time
        return st

    def _ensure_structure(self):
        return self._cycle.structure

    def _solve_static(self) -> None:
        self._iterations = self._cycle.solve_static(*unpack_law_arrays(self._laws)).iterations

    def _refresh(self) -> None:
        """Recompute the outputs (static solution first in initialisation mode); never raises."""
        try:
            st = self._ensure_structure()
            if self._cycle.needs_static:
                self._solve_static()
            self._take_outputs(self._outputs_of(st))
        except Exception as exc:  # anything raised here would be fatal for the host
            what = "static solution" if not self._cycle.stepping else "outputs"
            self.output_failed(f"{what} failed", exc)
            self._fail_outputs()

    def _outputs_of(self, st) -> list:
        """The outputs of the structure's current state, in the order of its output names
        (journal states, shaft speeds, then the step outputs of
        :func:`fmu_src.lifecycle.output_row`: the in-process transport's arithmetic); raises
        when it has no solution or an output is not finite."""
        if not st.solved:
            raise RuntimeError("the structure has no solution yet (no static solution)")
        if self._row is None or self._row[-1] is not st:  # (built per structure)
            nj, ns = 4 * st.nb, len(self._speeds)
            row = np.empty(len(self._output_names))
            row[nj:nj + ns] = self._speeds
            self._row = (st._state_outputs[:nj].copy(), st.nc, *transmission_error_terms(st),
                         st._gear_uv, nj + ns, row, st)
            if row.size != nj + ns + 2 * len(st.meshes) + 2 * st._gear_uv.shape[0]:
                raise RuntimeError(f"{row.size} outputs named for {nj} journal states, {ns} "
                                   f"speeds, {len(st.meshes)} meshes and "
                                   f"{st._gear_uv.shape[0]} gears")
        journal_idx, nc, te_idx, te_coef, gear_uv, first, row, _ = self._row
        output_row(journal_idx, nc, te_idx, te_coef, gear_uv, st._totals, st.x, st.v, row, first)
        outputs = row.tolist()
        if not math.isfinite(sum(outputs)):  # finite terms may overflow the sum
            bad = [n for n, x in zip(self._output_names, outputs, strict=True)
                   if not math.isfinite(x)]
            if bad:
                raise FloatingPointError(f"outputs not finite: {', '.join(bad)}")
        return outputs

    def _compute_support(self) -> None:
        try:
            from gear_fmu.modal.analyses import support_loads

            self._support = support_loads(self._ensure_structure()).ravel().tolist()
        except Exception as exc:  # anything raised here would be fatal for the host
            self.output_failed("support loads failed", exc)
            self._support = [math.nan] * len(self._support_names)

    # --- FMI life cycle -----------------------------------------------------------------------
    def setup_experiment(self, start_time, stop_time=None, tolerance=None):
        self._start_time = float(start_time)
        st = self._cycle.built
        if st is not None and st.n_steps == 0:
            st.t = self._start_time

    def exit_initialization_mode(self):
        try:
            info = self._cycle.exit_initialization(*unpack_law_arrays(self._laws))
            if info is not None:
                self._iterations = info.iterations
            self._error = None
        except Exception as exc:  # anything raised here would be fatal for the host
            self._cycle.phase = Phase.STEPPING  # steps are refused with the reason
            self._error = self.output_failed("initialisation failed", exc)
        self._arm_laws()
        self._dirty = True

    def do_step(self, current_time, step_size):
        """One Newmark step with the current laws; False (FMI discard) with a logged reason,
        after which the outputs read fmi2Error and steps are refused (module docstring)."""
        st = self._cycle.built
        try:
            if self._error is not None:
                raise RuntimeError(f"not stepping after an earlier failure ({self._error}); "
                                   "restore a saved state (fmi2SetFMUstate) to step again")
            if st is None or not self._cycle.stepping:
                raise RuntimeError("doStep before exitInitializationMode")
            periods = step_size / st.mesh_period
            if periods > MAX_STEP_MESH_PERIODS:
                raise ValueError(f"dt = {step_size:.6g} s spans {periods:.3g} mesh periods: a "
                                 f"step may span at most {MAX_STEP_MESH_PERIODS} (mesh period "
                                 f"{st.mesh_period:.6g} s)")
            info = self._cycle.step(current_time, step_size, *unpack_law_arrays(self._laws))
        except Exception as exc:  # anything raised here would be fatal for the host
            step = "?" if st is None else st.n_steps + 1
            failed = self.output_failed(f"doStep {step} from t = {current_time:.9g} s, dt = "
                                        f"{step_size:.6g} s failed", exc)
            self._read_status = 0  # a step reports discard, not the next read
            if st is not None and self._cycle.stepping:  # the structure is at no computed state
                if self._error is None:
                    self._error = failed
                self._fail_outputs()
            return False
        self._iterations = info.iterations
        try:  # computed now, so that the library serves the master's read of the journals
            self._take_outputs(self._outputs_of(st))
        except Exception:  # the read computes them again and reports why, with its status
            self._dirty = True
        return True

    # --- FMU state ----------------------------------------------------------------------------
    def _get_fmu_state(self):
        st = self._cycle.built
        return {
            "overrides": dict(self._overrides),
            "structure": None if st is None else st.get_state(),
            "laws": self._laws.copy(),
            "outputs": list(self._outputs),
            "iterations": self._iterations,
            "phase": self._cycle.phase.name,
            "dirty": self._dirty,
            "failed": self._failed,
            "error": self._error,
            "damping_kb": self._cycle.damping_kb,
        }

    def _check_sizes(self, state) -> None:
        """StateFormatError for a state of another gear train (its laws, outputs or damping
        reference sized for other numbers of bearings, meshes or gears)."""
        kb = state["damping_kb"]
        sizes = (len(state["laws"]), len(state["outputs"]), None if kb is None else kb.shape)
        mine = (self._laws.size, len(self._output_names),
                None if kb is None else (self._nb, 2, 2))
        if sizes != mine:
            raise StateFormatError(
                f"the FMU state is of another gear train: law inputs, outputs and damping "
                f"reference {sizes}, this FMU's {mine}")

    def _set_fmu_state(self, state):
        self._io[self._io_valid] = 0.0  # until the state is restored
        try:
            self._check_sizes(state)
            overrides = state["overrides"]
            if overrides != self._overrides:
                if overrides:
                    self._base.with_overrides(overrides)  # a case error before any change
                self._overrides = dict(overrides)
                self._reset_structure()
            saved = state["structure"]
            cycle = self._cycle
            if saved is None:
                cycle.built = None  # saved before the structure was built
                cycle.damping_kb = None
            else:
                st = self._ensure_structure()
                if isinstance(saved, dict):  # deserialised: checked against this structure
                    arrays = StateArrays(saved, "the FMU state's structure state")
                    saved = structure_state_from_arrays(arrays, st)
                    arrays.check_all_read()
                kb = state["damping_kb"]
                if kb is not None and kb is not cycle.damping_kb and (
                        cycle.damping_kb is None or not (kb == cycle.damping_kb).all()):
                    cycle.set_damping(kb)  # another instance, or another reference
                st.set_state(saved)
            self._laws[:] = state["laws"]
            self._outputs = list(state["outputs"])
            self._iterations = state["iterations"]
            cycle.phase = Phase[state["phase"]]
            self._arm_laws()
            self._dirty = state["dirty"]
            self._failed = state["failed"]
            self._error = state["error"]
            if not (self._dirty or self._failed):  # the saved outputs are the state's
                self._take_outputs(self._outputs)
        except Exception as exc:  # anything raised here would be fatal for the host
            self._error = self.output_failed("cannot restore the FMU state", exc)
            self._arm_laws()
            return FMI_ERROR
        return None

    # Serialised: ``overrides/<case field>``, ``laws`` (14 nb,), ``outputs``, ``iterations``,
    # ``phase`` (a :class:`fmu_src.lifecycle.Phase` name), the flags, ``error`` (text, absent
    # for none), ``damping_kb`` (nb, 2, 2) and
    # ``structure/...`` (fmu_src.states) once built (``has_structure``)
    STATE_KIND = STATE_KIND

    @classmethod
    def _state_to_arrays(cls, state) -> dict:
        out = overrides_to_arrays(state["overrides"])
        out |= {"laws": np.array(state["laws"], dtype=np.float64),
                "outputs": np.array(state["outputs"], dtype=np.float64),
                "iterations": np.int64(state["iterations"]),
                "has_structure": np.bool_(state["structure"] is not None)}
        out |= {name: np.bool_(state[name]) for name in _FLAGS}
        out["phase"] = np.str_(state["phase"])
        if state["error"] is not None:
            out["error"] = np.str_(state["error"])
        if state["damping_kb"] is not None:
            out["damping_kb"] = state["damping_kb"]
        if state["structure"] is not None:
            out |= nest("structure", structure_state_arrays(state["structure"]))
        return out

    @classmethod
    def _state_from_arrays(cls, arrays: StateArrays):
        state = {"overrides": overrides_from_arrays(arrays),
                 # their lengths are checked against the instance's train when set
                 "laws": arrays.array("laws", "float64", (None,)),
                 "outputs": arrays.array("outputs", "float64", (None,)).tolist(),
                 "iterations": arrays.int("iterations"),
                 "error": arrays.text("error") if arrays.has("error") else None,
                 "damping_kb": (arrays.array("damping_kb", "float64", (None, 2, 2))
                                if arrays.has("damping_kb") else None),
                 # checked against the structure when set
                 "structure": arrays.part("structure") if arrays.bool("has_structure") else None}
        state |= {name: arrays.bool(name) for name in _FLAGS}
        phase = arrays.text("phase")
        if phase not in Phase.__members__:
            raise StateFormatError(f"the FMU state's phase {phase!r} is not one of "
                                   f"{', '.join(Phase.__members__)}")
        state["phase"] = phase
        return state
