"""pythonfmu slave of the gear-shaft FMU: the contract's variables around one ``Structure``.

Nothing physical happens here: the slave builds :class:`gear_fmu.structure.Structure` from a case
file (through :mod:`fmu_src.case` and :mod:`fmu_src.description`, the system description
shared with the in-process runs), keeps the 40 affine-law inputs (layout:
:func:`fmu_src.contract.unpack_laws`), and maps the FMI calls onto the structure:

* initialisation mode: outputs are the static solution for the current laws, solved in the
  getter when an input changed since the last solve (the master iterates X0 this way);
* ``exitInitializationMode``: static solution if none was computed yet, then
  ``set_damping_reference`` with the symmetric part of the current Kb laws;
* ``doStep(t, dt)``: one ``Structure.step`` from t (must be the structure's time) to t + dt;
* ``get/setFMUstate``: structure state, laws and outputs (exact rollback); pickle serialises.

Every failure (a NewmarkConvergenceError, non-finite laws, a bad case file) is caught, logged
with status error and reported as a non-OK status (doStep returns False) or NaN outputs: a Python
exception escaping a pythonfmu callback would be fatal for the instance and its host.
"""

from __future__ import annotations

import math
import pickle
from pathlib import Path

from pythonfmu import Fmi2Slave
from pythonfmu.default_experiment import DefaultExperiment
from pythonfmu.enums import Fmi2Status

from fmu_src.contract import (
    GEAR_DEFAULT_CASE,
    GEAR_OUTPUTS,
    GEAR_VARIABLES,
    journal_output_names,
    law_input_names,
    support_load_names,
    unpack_laws,
)
from fmu_src.slave_support import (
    describe_exception,
    register_contract_variable,
    release_python_state_at_exit,
)

__all__ = ["GearShaftSlave"]

DEFAULT_CASE = GEAR_DEFAULT_CASE

_LAWS = law_input_names()
_OUTPUTS = [*journal_output_names(), *(name for name, _, _ in GEAR_OUTPUTS)]
_SUPPORT = support_load_names()
_NAN_OUTPUTS = [math.nan] * len(_OUTPUTS)


def _default_step() -> float:
    """The time step of the shipped case (mesh period / steps per mesh period) [s]."""
    from fmu_src.case import load_case
    from fmu_src.description import time_step

    return time_step(load_case(Path(DEFAULT_CASE).stem))


PAPER_STEP = _default_step()


class GearShaftSlave(Fmi2Slave):
    """Gear-shaft structure as an FMI 2.0 co-simulation slave (module docstring)."""

    author = "gear-shaft-bearing contributors"
    license = "MIT"
    #: two mesh periods of the shipped paper case at its time step (``fmpy simulate`` defaults)
    default_experiment = DefaultExperiment(start_time=0.0, stop_time=64 * PAPER_STEP,
                                           step_size=PAPER_STEP)

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.description = (
            "Gear-shaft structure (Timoshenko shafts, distributed gear mesh, Newmark/Newton/"
            "contact step) driven by four affine bearing laws; global frame, SI units "
            "(Baguet & Jacquenot 2010)."
        )
        starts = {v.name: v.start for v in GEAR_VARIABLES}
        self._case_file = ""
        self._laws = [float(starts[n]) for n in _LAWS]  # never rebound: setters hold it
        self._outputs = list(_NAN_OUTPUTS)
        self._iterations = 0
        self._support: list | None = None
        self._structure = None
        self._start_time = 0.0
        self._stepping = False  # after exitInitializationMode
        self._need_static = True  # initialisation: laws changed since the last static solve
        self._have_static = False  # the structure holds a static solution
        self._dirty = True  # outputs must be recomputed from the structure
        self._error: str | None = None  # a failure that forbids stepping (build, initialisation)
        release_python_state_at_exit(self.resources, type(self).__name__)
        self._register_all()

    # --- FMI plumbing ------------------------------------------------------------------------
    def _register_all(self) -> None:
        index = {name: i for i, name in enumerate(_LAWS)}
        out_index = {name: i for i, name in enumerate(_OUTPUTS)}
        sup_index = {name: i for i, name in enumerate(_SUPPORT)}
        for v in GEAR_VARIABLES:
            if v.name == "case_file":
                register_contract_variable(self, v, lambda: self._case_file, self._set_case_file)
            elif v.name in index:
                i = index[v.name]
                register_contract_variable(self, v, self._law_getter(i), self._law_setter(i))
            elif v.name in out_index:
                register_contract_variable(self, v, self._output_getter(out_index[v.name]))
            elif v.name == "iterations":
                register_contract_variable(self, v, self._get_iterations)
            elif v.name in sup_index:
                register_contract_variable(self, v, self._support_getter(sup_index[v.name]))
            else:  # pragma: no cover - the contract and this slave disagree
                raise RuntimeError(f"gear-shaft slave has no handler for variable {v.name!r}")
        vr = {v.name: v.value_reference for v in self.vars.values()}
        self._law_vrs = [vr[n] for n in _LAWS]
        self._journal_vrs = [vr[n] for n in _OUTPUTS[:16]]

    # The master sets all 40 laws and reads the 16 journal states in one call each: served
    # without the per-variable loop of Fmi2Slave.set_real/get_real (same effect, ~2x cheaper).
    def set_real(self, vrs, values):
        if vrs == self._law_vrs:
            laws = self._laws
            if self._stepping:
                laws[:] = values
            elif laws != values:
                laws[:] = values
                self._need_static = True
                self._dirty = True
        else:
            super().set_real(vrs, values)

    def get_real(self, vrs):
        if vrs == self._journal_vrs:
            if self._dirty:
                self._refresh()
            return self._outputs[:16]
        return super().get_real(vrs)

    def _set_case_file(self, value) -> None:
        value = str(value)
        if value != self._case_file:
            self._case_file = value
            self._structure = None
            self._support = None
            self._have_static = False
            self._need_static = True
            self._dirty = True
            self._error = None

    def _law_getter(self, i):
        laws = self._laws
        return lambda: laws[i]

    def _law_setter(self, i):
        laws = self._laws

        def set_(value):
            if laws[i] != value:
                laws[i] = value
                if not self._stepping:  # step mode: the laws act at the next doStep only
                    self._need_static = True
                    self._dirty = True
        return set_

    def _output_getter(self, k):
        def get():
            if self._dirty:
                self._refresh()
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
            return self._support[k]
        return get

    def _log_error(self, what: str, exc: BaseException) -> str:
        msg = f"{self.instance_name}: {what}: {describe_exception(exc)}"
        self.log(msg, Fmi2Status.error)
        return msg

    # --- physics ------------------------------------------------------------------------------
    def _case_path(self) -> str:
        if self._case_file:
            return self._case_file
        if self.resources is not None and (Path(self.resources) / DEFAULT_CASE).is_file():
            return str(Path(self.resources) / DEFAULT_CASE)
        return Path(DEFAULT_CASE).stem  # the case shipped with the package, by name

    def _ensure_structure(self):
        if self._structure is None:
            from fmu_src.case import load_case
            from fmu_src.description import structure

            st = structure(load_case(self._case_path()))
            st.t = self._start_time
            self._structure = st
        return self._structure

    def _solve_static(self) -> None:
        st = self._ensure_structure()
        laws = unpack_laws(self._laws)
        info = st.static(laws.f0, laws.kb, laws.cb)
        self._iterations = info.iterations
        self._need_static = False
        self._have_static = True

    def _refresh(self) -> None:
        """Recompute the outputs (static solution first in initialisation mode); never raises."""
        try:
            st = self._ensure_structure()
            if self._need_static and not self._stepping:
                self._solve_static()
            if st.mesh_state is None:
                raise RuntimeError("the structure has no solution yet (no static solution)")
            ms = st.mesh_state
            g = st.gear_displacements()
            self._outputs = [*st.journal_states().ravel().tolist(),
                             float(ms.total_load), float(ms.transmission_error),
                             float(g[0, 0]), float(g[0, 1]), float(g[1, 0]), float(g[1, 1])]
        except Exception as exc:  # anything raised here would be fatal for the host
            what = "static solution" if not self._stepping else "outputs"
            self._log_error(f"{what} failed", exc)
            self._outputs = list(_NAN_OUTPUTS)
        self._dirty = False

    def _compute_support(self) -> None:
        try:
            from gear_fmu.analyses import support_loads

            self._support = support_loads(self._ensure_structure()).ravel().tolist()
        except Exception as exc:  # anything raised here would be fatal for the host
            self._log_error("support loads failed", exc)
            self._support = [math.nan] * len(_SUPPORT)

    # --- FMI life cycle -----------------------------------------------------------------------
    def setup_experiment(self, start_time, stop_time=None, tolerance=None):
        self._start_time = float(start_time)
        if self._structure is not None and self._structure.n_steps == 0:
            self._structure.t = self._start_time

    def exit_initialization_mode(self):
        self._stepping = True
        try:
            st = self._ensure_structure()
            if not self._have_static:
                self._solve_static()
            kb = unpack_laws(self._laws).kb
            st.set_damping_reference(0.5 * (kb + kb.transpose(0, 2, 1)))
            self._error = None
        except Exception as exc:  # anything raised here would be fatal for the host
            self._error = self._log_error("initialisation failed", exc)
        self._dirty = True

    def do_step(self, current_time, step_size):
        """One Newmark step with the current laws; False (FMI discard) with a logged reason."""
        st = self._structure
        try:
            if self._error is not None:
                raise RuntimeError(f"not stepping after an earlier failure ({self._error})")
            if st is None or not self._stepping:
                raise RuntimeError("doStep before exitInitializationMode")
            if abs(current_time - st.t) > 1e-9 * max(step_size, abs(current_time)):
                raise ValueError(f"doStep from t = {current_time!r} s but the structure is at "
                                 f"t = {st.t!r} s")
            laws = unpack_laws(self._laws)
            info = st.step(step_size, laws.f0, laws.kb, laws.cb)
        except Exception as exc:  # anything raised here would be fatal for the host
            step = "?" if st is None else st.n_steps + 1
            self._log_error(f"doStep {step} from t = {current_time:.9g} s, dt = "
                            f"{step_size:.6g} s failed", exc)
            return False
        self._iterations = info.iterations
        self._dirty = True
        return True

    # --- FMU state ----------------------------------------------------------------------------
    def _get_fmu_state(self):
        st = self._structure
        return {
            "case_file": self._case_file,
            "structure": None if st is None else st.get_state(),
            "laws": list(self._laws),
            "outputs": list(self._outputs),
            "iterations": self._iterations,
            "need_static": self._need_static,
            "have_static": self._have_static,
            "dirty": self._dirty,
            "error": self._error,
        }

    def _set_fmu_state(self, state):
        try:
            self._set_case_file(state["case_file"])
            self._laws[:] = state["laws"]
            if state["structure"] is None:
                self._structure = None  # saved before the structure was built
            else:
                self._ensure_structure().set_state(state["structure"])
            self._outputs = list(state["outputs"])
            self._iterations = state["iterations"]
            self._need_static = state["need_static"]
            self._have_static = state["have_static"]
            self._dirty = state["dirty"]
            self._error = state["error"]
        except Exception as exc:  # anything raised here would be fatal for the host
            self._error = self._log_error("cannot restore the FMU state", exc)

    @staticmethod
    def _fmu_state_to_bytes(state) -> bytes:
        return pickle.dumps(state, protocol=pickle.HIGHEST_PROTOCOL)

    @staticmethod
    def _fmu_state_from_bytes(state: bytes):
        return pickle.loads(state)
