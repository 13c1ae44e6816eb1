"""pythonfmu slave of the transmission FMU: the whole coupled system in one FMU.

The gear-shaft structure of any gear train, its bearings (each of its own
``bearings.<name>.model``) and the iterative master
(:class:`orchestrator.coupling.master.Master`, in-process slaves built by
:func:`orchestrator.coupling.system.build_master`) inside one FMI 2.0 co-simulation slave, so
that a tool that does not iterate FMUs (libcosim, OMSimulator, ecos) gets ``gsb run``'s answer.
Written by ``gsb export-fmu`` (:func:`fmu_src.build.fmus.build_transmission_fmu`), which puts
the case into its resources (``case.toml``).

* Parameters: every case field but the run length (:func:`fmu_src.contract.transmission_fields`)
  and ``bearing_fmu``, a bearing FMU of the user's own (run through fmpy, in the host's
  Python) for every bearing instead of their models; a change rebuilds the system.
* Outputs (:func:`fmu_src.contract.transmission_output_names`): each bearing's journal state
  and film force, named after the bearing, each mesh's force and transmission error, named
  after the mesh.
* Input ``torque`` [N m]: the input torque, held over a communication step
  (:meth:`gear_fmu.structure.Structure.set_torque`); until set, the case's ``drive.torque``.
* Input ``speed`` [rad/s]: the input speed reached at the end of the next communication step,
  ramped over it (:meth:`gear_fmu.structure.Structure.follow_speed`: a run-up driven by the
  host); set in initialisation, the parameter ``drive.speed``; until set, the case's speed
  and profile. At most the parameter ``max_speed``, for which the time step is sized.
* Initialisation: the outputs are the static solution X0 (Sec. 2.2.3), solved when first read
  or at ``exitInitializationMode``.
* ``doStep(t, h)``: ``n = ceil(h / (dt (1 + 1e-4)))`` equal coupled steps of ``h / n``, dt the
  case's time step: a step a host rounds (libcosim keeps whole nanoseconds) is taken as it comes
  if within 1e-4 of dt, and a longer one is cut, never longer than dt. A step that is dt to the
  rounding of the host's clock (:func:`is_case_step`: fmpy steps to ``k * h``, so its steps
  differ from dt in their last bits) is taken as dt: the steps are then ``gsb run``'s, bit for
  bit, whatever the host's arithmetic.
* Time: the FMU's time is the host's, re-anchored at every ``doStep`` to ``t + h`` (a step must
  start there, to 1e-9 relative); the structure keeps its own clock, the sum of the steps it
  took (``gsb run``'s at the case's step), which differs from the host's by rounding only
  (:meth:`TransmissionSlave.do_step`).
* ``get/setFMUstate`` and serialisation: the master's checkpoint (structure, bearing warm starts,
  laws) with the parameters, the torque and the time. A state set into an instance that has not
  solved the same static problem solves it first (as a resumed run does), then continues bit
  for bit.

A failed step returns fmi2Discard with the reason in the log and refuses further steps until a
state is set; a failed output read returns fmi2Error (a Python exception escaping a pythonfmu
callback would be fatal for the host).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from pythonfmu.default_experiment import DefaultExperiment

from bearing_fmu.blas_threads import ONE_BLAS_THREAD
from fmu_src.case import varying_speed_refusal
from fmu_src.contract import (
    BEARING_RESOURCE,
    ValueRefused,
    transmission_output_names,
    transmission_variables,
)
from fmu_src.description import mesh_period, speed_profile, time_step
from fmu_src.slaves.support import (
    FMI_ERROR,
    ContractSlave,
    case_parameter,
    overrides_from_arrays,
    overrides_to_arrays,
)
from fmu_src.state_codec import StateArrays, StateFormatError
from gear_fmu.speed_profile import SpeedProfile
from orchestrator.coupling.system import build_master

__all__ = ["CASE_RESOURCE", "CLOCK_ULPS", "STATE_KIND", "TransmissionSlave", "internal_steps",
           "is_case_step"]

#: the case a transmission FMU carries, in its resources
CASE_RESOURCE = "case.toml"
#: the kind tag of this slave's serialised states (fmu_src.state_codec)
STATE_KIND = "gsb.transmission_fmu_state"
#: a communication step within this fraction above the case's step is taken in one step
STEP_SLACK = 1e-4
#: a communication step within this many units in the last place of the host's time of the
#: case's step is the case's step (:func:`is_case_step`)
CLOCK_ULPS = 4
#: a step must start at the FMU's time to this fraction (of the time, or of a longer step);
#: the structure's clock is set to the host's time when they differ by more
CLOCK_SLACK = 1e-9



def internal_steps(h: float, dt: float) -> int:
    """How many equal steps a communication step ``h`` [s] takes, each at most ``dt`` [s]
    (to :data:`STEP_SLACK`): ``internal_steps(2 * dt, dt) == 2``,
    ``internal_steps(dt * (1 + 1e-6), dt) == 1``."""
    return max(1, math.ceil(h / (dt * (1.0 + STEP_SLACK))))


def is_case_step(t: float, h: float, dt: float) -> bool:
    """Whether a communication step ``h`` [s] from the host's time ``t`` [s] is the case's step
    ``dt`` [s] to the rounding of the host's clock: ``|h - dt| <= CLOCK_ULPS ulp(|t| + h)``.

    A host whose communication points are ``t_k = t0 + k dt`` rounded to doubles (fmpy's
    ``start + k * output_interval``; libcosim's nanosecond count over 1e9) passes
    ``h = t_(k+1) - t_k`` (exact: Sterbenz): each point carries at most one rounding of the
    product and one of the sum, half an ulp each of at most ``ulp(t_(k+1))``, so
    ``|h - dt| <= 2 ulp(t_(k+1))``; :data:`CLOCK_ULPS` doubles that. A step that differs from
    dt by more (libcosim's 23,236 ns against the paper's 23,236.632 ns: 6.3e-10 s, 2.8e6 ulps
    of a time of 1 s) is not the case's step."""
    return abs(h - dt) <= CLOCK_ULPS * math.ulp(abs(t) + h)


class TransmissionSlave(ContractSlave):
    """The transmission (structure, bearings, master) as an FMI 2.0 slave (module docstring)."""

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.description = (
            "Gear-shaft-bearing transmission (a parallel-axis gear train: Timoshenko shafts, "
            "distributed gear meshes, journal bearings) with its iterative co-simulation master "
            "inside; global frame, SI units (Baguet & Jacquenot 2010).")

        self._base = self._base_case()
        #: the Real outputs of the carried case's train, in the order of the variables
        self._output_names = transmission_output_names(self._base)
        self._nan = [math.nan] * len(self._output_names)
        step = time_step(self._base)
        stop = self._base["simulation.mesh_periods"] * mesh_period(self._base)
        self.default_experiment = DefaultExperiment(start_time=0.0, stop_time=stop,
                                                    step_size=step)
        self._overrides: dict = {}  # case field -> value set through a parameter
        self._bearing_fmu = ""  # the parameter bearing_fmu
        self._torque: float | None = None  # the input, once a host has set it
        self._speed: float | None = None  # the input speed, once a host has set it stepping
        self._max_speed: float | None = None  # the parameter; None: the case's top speed
        self._start_time = 0.0
        self._time = 0.0  # the FMU's time: the host's last communication point
        self._master = None
        self._static_key = None  # _key() of the master's static solution
        self._stepping = False
        self._outputs = list(self._nan)
        self._iterations = 0
        self._steps = 0
        self._error: str | None = None  # a failure that forbids stepping
        carried = self.resources is not None and (Path(self.resources) / BEARING_RESOURCE).is_file()
        self._register_all(transmission_variables(self._base,
                                                  BEARING_RESOURCE if carried else ""))

    def _base_case(self):
        from fmu_src.case import load_case, shipped_case

        path = None if self.resources is None else Path(self.resources) / CASE_RESOURCE
        if path is not None and path.is_file():
            return load_case(path)
        return shipped_case("baguet2010_spur")

    # --- FMI plumbing ------------------------------------------------------------------------
    def _register_all(self, variables) -> None:
        out_index = {name: i for i, name in enumerate(self._output_names)}
        for v in variables:
            if v.name == "bearing_fmu":
                self._bearing_fmu = v.start
                self.register_contract_variable(v, lambda: self._bearing_fmu,
                                                self._set_bearing_fmu)
            elif v.name == "max_speed":
                self.register_contract_variable(v, self._get_max_speed, self._set_max_speed)
            elif v.causality == "parameter":
                self.register_contract_variable(
                    v, *case_parameter(self, v.name, self._drop_master))
            elif v.name == "torque":
                self.register_contract_variable(v, self._get_torque, self._set_torque)
            elif v.name == "speed":
                self.register_contract_variable(v, self._get_speed, self._set_speed)
            elif v.name in out_index:
                self.register_contract_variable(v, self._output_getter(out_index[v.name]))
            elif v.name == "iterations":
                self.register_contract_variable(v, lambda: self._refreshed()._iterations)
            elif v.name == "steps":
                self.register_contract_variable(v, lambda: self._steps)
            else:  # pragma: no cover - the contract and this slave disagree
                raise RuntimeError(f"transmission slave has no handler for {v.name!r}")
        self._output_of_vr = {v.value_reference: out_index[v.name]
                              for v in self.vars.values() if v.name in out_index}

    # A host reads the outputs after every step: served without the per-variable getters
    # when stepping without a failure (the same values, several times cheaper).
    def get_real(self, vrs):
        if self._stepping and self._error is None:
            try:
                return [self._outputs[self._output_of_vr[vr]] for vr in vrs]
            except KeyError:
                pass  # not only outputs
        return super().get_real(vrs)

    def _set_bearing_fmu(self, value) -> None:
        if value != self._bearing_fmu:
            self._bearing_fmu = value
            self._drop_master()

    def _bearing_fmu_path(self) -> str | None:
        """The bearing FMU of the user's own (``bearing_fmu``: relative to the resources),
        or None for the case's model."""
        if not self._bearing_fmu:
            return None
        path = Path(self._bearing_fmu)
        if not path.is_absolute() and self.resources is not None:
            path = Path(self.resources) / path
        if not path.is_file():
            raise FileNotFoundError(f"bearing_fmu = {self._bearing_fmu!r}: no such file "
                                    f"({path})")
        return str(path)

    def _get_torque(self) -> float:
        return self.case()["drive.torque"] if self._torque is None else self._torque

    def _set_torque(self, value) -> None:
        self._torque = float(value)
        if not self._stepping:  # in initialisation a new torque is a new static problem
            self._outputs = None

    def _top_speed(self) -> float:
        """The case's highest input speed [rad/s] (drive.speed, drive.speed_profile)."""
        return speed_profile(self.case()).max_speed

    def _get_max_speed(self) -> float:
        return self._top_speed() if self._max_speed is None else self._max_speed

    def _max_speed_below(self, value: float) -> str | None:
        """Why ``value`` [rad/s] cannot be ``max_speed``: below the case's highest speed."""
        top = self._top_speed()
        if value < top:
            return (f"below {top:g} rad/s, the case's highest speed (drive.speed, "
                    f"drive.speed_profile)")
        return None

    def _set_max_speed(self, value) -> None:
        value = float(value)
        why = self._max_speed_below(value)
        if why is not None:
            raise ValueRefused(f"max_speed = {value!r} rad/s refused: {why}")
        if value != self._max_speed:
            self._max_speed = value
            self._drop_master()

    def _time_step(self) -> float:
        """The case's time step [s], or shorter as the fastest mesh's at ``max_speed`` (a
        ``drive.speed`` set after it may have passed it)."""
        dt = time_step(self.case())
        if self._max_speed is None or self._max_speed == self._top_speed():
            return dt
        why = self._max_speed_below(self._max_speed)
        if why is not None:
            raise ValueError(f"max_speed = {self._max_speed!r} rad/s: {why}")
        return dt * (self._top_speed() / self._max_speed)

    def _get_speed(self) -> float:
        if self._speed is not None:
            return self._speed
        if self._master is not None and self._stepping:
            st = self._master.structure.physics
            return st.input_speed_at(st.t)
        return self.case()["drive.speed"]

    def _set_speed(self, value) -> None:
        """In initialisation the parameter drive.speed; stepping, the speed the next
        communication step ramps to (refused above ``max_speed``, and for a case that
        cannot follow a varying speed: linear bearings, a film at rest)."""
        value = float(value)
        if not self._stepping:
            case_parameter(self, "drive.speed", self._drop_master)[1](value)
            return
        if value > self._get_max_speed():
            raise ValueRefused(f"speed = {value!r} rad/s refused: above max_speed = "
                               f"{self._get_max_speed():g} rad/s, the highest speed the time "
                               f"step is sized for (set the parameter max_speed before "
                               f"initialisation)")
        now = self._get_speed()
        if value != now:
            why = varying_speed_refusal(self.case().values, min(value, now),
                                        models=not self._bearing_fmu)
            if why is not None:
                raise ValueRefused(f"speed = {value!r} rad/s refused: {why}")
        self._speed = value

    def _follow_speed(self, st, n: int, h: float) -> None:
        """The host's speed input over the next ``n`` steps of ``h`` [s] from the structure's
        time: a ramp to it ending where the last of them ends
        (:meth:`gear_fmu.structure.Structure.follow_speed`; nothing before a host sets it)."""
        if self._speed is None:
            return
        end = st.t
        for _ in range(n):  # the structure's clock: the sum of its steps
            end = end + h
        st.follow_speed(end, self._speed)

    def _output_getter(self, k):
        def get():
            return self._refreshed()._outputs[k]
        return get

    def _refreshed(self):
        """Self, with the outputs computed (the static solution in initialisation); a failure
        makes the current read return fmi2Error."""
        if self._outputs is None or (not self._stepping and self._static_key != self._key()):
            try:
                self._solve_static()
            except Exception as exc:  # anything raised here would be fatal for the host
                self._error = self.output_failed("static solution failed", exc)
                self._outputs = list(self._nan)
        if self._error is not None and any(map(math.isnan, self._outputs)):
            self._read_status = FMI_ERROR
        return self

    # --- the system ---------------------------------------------------------------------------
    def case(self):
        """The case the FMU simulates: its carried case with the parameters' values."""
        return self._base.with_overrides(self._overrides) if self._overrides else self._base

    def _key(self):
        return (repr(sorted(self._overrides.items())), self._bearing_fmu), self._get_torque()

    def _drop_master(self) -> None:
        if self._master is not None:
            self._master.close()
        self._master = None
        self._static_key = None
        self._stepping = False
        self._outputs = None
        self._error = None

    def _solve_static(self) -> None:
        """Build the master for the current parameters and torque and solve X0."""
        self._drop_master()
        case = self.case()
        fmu = self._bearing_fmu_path()
        n = len(case.names("bearings"))
        master = build_master(case, in_process=True,
                              fmus=None if fmu is None else {"bearings": [fmu] * n})
        master.structure.physics.t = self._time = self._start_time
        master.structure.physics.set_torque(self._get_torque())
        report = master.solve_static()
        self._master, self._static_key = master, self._key()
        self._iterations = report.iterations
        self._record(report.states, report.bearing_force)

    def _record(self, states, bearing_force) -> None:
        """The outputs: journal states (nb, 4) [m, m/s], film forces (nb, 2) [N], and the
        structure's mesh forces [N] and transmission errors [m] now (n_meshes,)."""
        forces, errors, _ = self._master.structure.step_outputs()
        self._outputs = [*states.ravel().tolist(), *bearing_force.ravel().tolist(),
                         *forces.tolist(), *errors.tolist()]

    # --- FMI life cycle -----------------------------------------------------------------------
    def setup_experiment(self, start_time, stop_time=None, tolerance=None):
        if float(start_time) != self._start_time:
            self._start_time = float(start_time)
            self._drop_master()

    def exit_initialization_mode(self):
        self._refreshed()
        if self._error is None:
            try:
                self._master.exit_initialization()
                self._dt = self._time_step()
            except Exception as exc:  # anything raised here would be fatal for the host
                self._error = self.output_failed("initialisation failed", exc)
        self._stepping = True

    def do_step(self, current_time, step_size):
        """``internal_steps`` coupled steps over [t, t + h] with the torque held; False (FMI
        discard) with a logged reason when one fails or cannot start.

        The FMU's time is the host's: a step starts at the FMU's time (to :data:`CLOCK_SLACK`,
        for a host that computes its next point otherwise than ``t + h``) and moves it to
        ``t + h``. The structure steps from its own clock, the sum of the steps it took: a step
        that is the case's to the host's rounding (:func:`is_case_step`) is taken as dt, as
        ``gsb run`` takes it, so the states are ``gsb run``'s bit for bit whichever rounding
        the host's clock has. That clock and the structure's are two roundings of the same
        times ``t0 + k dt``: the sum of k steps is within ``k/2`` ulps of its time, ``k eps / 2``
        relative (``gsb run``'s master allows its own clock :data:`CLOCK_SLACK` too); cut steps
        add up as slowly (3.5e-11 relative after 10^6 steps of 100,000 ns in 5). Clocks that
        part by more than :data:`CLOCK_SLACK` (a host whose steps all round one way, after
        millions of steps) are joined again: the structure's is set to the host's."""
        try:
            if self._error is not None:
                raise RuntimeError(f"not stepping after an earlier failure ({self._error})")
            if not self._stepping:
                raise RuntimeError("doStep before exitInitializationMode")
            st = self._master.structure.physics
            slack = CLOCK_SLACK * max(step_size, abs(current_time))
            if abs(current_time - self._time) > slack:
                raise ValueError(f"a step from t = {current_time!r} s but the transmission is "
                                 f"at t = {self._time!r} s (restore a state to go back)")
            if abs(current_time - st.t) > slack:  # the clocks parted (not in 1e7 steps)
                st.t = current_time
            if not (step_size > 0.0 and math.isfinite(step_size)):
                raise ValueError(f"communication step {step_size!r} s must be finite and > 0")
            if is_case_step(current_time, step_size, self._dt):
                n, h = 1, self._dt
            else:
                n = internal_steps(step_size, self._dt)
                h = step_size / n
            st.set_torque(self._get_torque())
            self._follow_speed(st, n, h)
            with ONE_BLAS_THREAD:  # once for the n steps (module bearing_fmu.blas_threads)
                iterations, last = self._steps_of(st, n, h)
        except Exception as exc:  # anything raised here would be fatal for the host
            self._error = self.output_failed(
                f"doStep from t = {current_time:.9g} s, h = {step_size:.6g} s failed", exc)
            self._read_status = 0  # the step reports discard, not the next read
            self._outputs = list(self._nan)
            return False
        self._iterations = iterations
        self._time = current_time + step_size
        self._record(*last)
        return True

    def _steps_of(self, st, n: int, h: float):
        """``n`` coupled steps of ``h`` [s]: in compiled blocks where the master takes them
        (the same steps as one by one), else one by one. Their coupled iterations, and the
        last step's journal states and bearing forces; the error of a step that fails, the
        steps before it taken."""
        master, done, iterations = self._master, 0, 0
        while done < n:
            block = master.steps_from(st.t, h, n - done)
            if block is None:
                report = master.step(st.t, h)
                done += 1
                self._steps += 1
                iterations += report.iterations
                last = (report.states, report.bearing_force)
                continue
            done += block.count
            self._steps += block.count
            iterations += int(block.iterations.sum())
            if block.error is not None:
                raise block.error
            last = (block.states[-1], block.bearing_force[-1])
        return iterations, last

    def terminate(self):
        if self._master is not None:
            self._master.close()

    # --- FMU state ----------------------------------------------------------------------------
    def _get_fmu_state(self):
        master = self._master
        profile = None if master is None else master.structure.physics.loads.profile
        return {"overrides": dict(self._overrides), "bearing_fmu": self._bearing_fmu,
                "torque": self._torque, "speed": self._speed, "max_speed": self._max_speed,
                "profile": None if profile is None else (profile.times, profile.speeds,
                                                         profile.start_angle),
                "start_time": self._start_time, "time": self._time,
                "stepping": self._stepping, "static_key": self._static_key,
                "checkpoint": None if master is None else master.checkpoint(),
                "outputs": None if self._outputs is None else list(self._outputs),
                "iterations": self._iterations, "steps": self._steps, "error": self._error}

    def _set_fmu_state(self, state):
        try:
            outputs = state["outputs"]
            if outputs is not None and len(outputs) != len(self._output_names):
                raise StateFormatError(f"the FMU state holds {len(outputs)} outputs, this "
                                       f"FMU's train {len(self._output_names)}")
            if state["overrides"] != self._overrides:
                if state["overrides"]:
                    self._base.with_overrides(state["overrides"])  # a case error before a change
                self._overrides = dict(state["overrides"])
                self._drop_master()
            if state["bearing_fmu"] != self._bearing_fmu:
                self._bearing_fmu = state["bearing_fmu"]
                self._drop_master()
            if state["max_speed"] != self._max_speed:
                self._max_speed = state["max_speed"]
                self._drop_master()
            self._start_time = state["start_time"]
            blob = state["checkpoint"]
            if blob is None:
                self._drop_master()
                self._torque = state["torque"]
            else:
                static_torque = state["static_key"][1]
                self._torque = static_torque
                if self._master is None or self._static_key != self._key():
                    self._solve_static()  # the static problem the state continues from
                if state["stepping"] and not self._stepping:
                    self._master.exit_initialization()
                    self._dt = self._time_step()
                self._master.restore(blob)
                self._restore_profile(state["profile"])
                self._torque = state["torque"]
            self._speed = state["speed"]
            self._time = state["time"]
            if self._time is None:  # a state of an FMU before the two clocks: the structure's
                self._time = (self._start_time if self._master is None
                              else self._master.structure.physics.t)
            self._stepping = state["stepping"]
            self._outputs = None if outputs is None else list(outputs)
            self._iterations, self._steps = state["iterations"], state["steps"]
            self._error = state["error"]
        except Exception as exc:  # anything raised here would be fatal for the host
            self._error = self.output_failed("cannot restore the FMU state", exc)
            return FMI_ERROR
        return None

    def _restore_profile(self, saved) -> None:
        """The structure's speed profile of a state (``(times, speeds, start_angle)``, None
        for none), set only where it is not the one the structure has (the case's, or one a
        speed input continued)."""
        st = self._master.structure.physics
        now = st.loads.profile
        if saved is None:
            if now is not None and now.start_angle is not None:
                case_profile = speed_profile(self.case())
                st.set_profile(case_profile if case_profile.varies else None)
            return
        times, speeds, start = saved
        if now is None or (now.times, now.speeds, now.start_angle) != (times, speeds, start):
            st.set_profile(SpeedProfile(tuple(times), tuple(speeds), start_angle=start))

    STATE_KIND = STATE_KIND

    @classmethod
    def _state_to_arrays(cls, state) -> dict:
        out = overrides_to_arrays(state["overrides"])
        out |= {"start_time": np.float64(state["start_time"]),
                "time": np.float64(state["time"]),
                "bearing_fmu": np.str_(state["bearing_fmu"]),
                "stepping": np.bool_(state["stepping"]),
                "iterations": np.int64(state["iterations"]), "steps": np.int64(state["steps"])}
        for key in ("torque", "speed", "max_speed"):
            if state[key] is not None:
                out[key] = np.float64(state[key])
        if state["profile"] is not None:
            times, speeds, start = state["profile"]
            out["profile_times"] = np.array(times, dtype=np.float64)
            out["profile_speeds"] = np.array(speeds, dtype=np.float64)
            out["profile_start_angle"] = np.float64(np.nan if start is None else start)
        if state["static_key"] is not None:
            out["static_torque"] = np.float64(state["static_key"][1])
        if state["checkpoint"] is not None:
            out["checkpoint"] = np.frombuffer(state["checkpoint"], dtype=np.uint8)
        if state["outputs"] is not None:
            out["outputs"] = np.array(state["outputs"], dtype=np.float64)
        if state["error"] is not None:
            out["error"] = np.str_(state["error"])
        return out

    @classmethod
    def _state_from_arrays(cls, arrays: StateArrays):
        overrides = overrides_from_arrays(arrays)
        has = arrays.has
        bearing_fmu = arrays.text("bearing_fmu")
        return {"overrides": overrides, "bearing_fmu": bearing_fmu,
                "torque": arrays.float("torque") if has("torque") else None,
                "speed": arrays.float("speed") if has("speed") else None,
                "max_speed": arrays.float("max_speed") if has("max_speed") else None,
                "profile": _profile_from_arrays(arrays),
                "start_time": arrays.float("start_time"),
                "time": arrays.float("time") if has("time") else None,
                "stepping": arrays.bool("stepping"),
                "static_key": (((repr(sorted(overrides.items())), bearing_fmu),
                                arrays.float("static_torque"))
                               if has("static_torque") else None),
                "checkpoint": (arrays.array("checkpoint", "uint8").tobytes()
                               if has("checkpoint") else None),
                "outputs": (arrays.array("outputs", "float64", (None,)).tolist()
                            if has("outputs") else None),
                "iterations": arrays.int("iterations"), "steps": arrays.int("steps"),
                "error": arrays.text("error") if has("error") else None}


def _profile_from_arrays(arrays: StateArrays):
    """``(times, speeds, start_angle)`` of a state's speed profile, None without one."""
    if not arrays.has("profile_times"):
        return None
    times = tuple(arrays.array("profile_times", "float64", (None,)).tolist())
    speeds = tuple(arrays.array("profile_speeds", "float64", (len(times),)).tolist())
    start = arrays.float("profile_start_angle")
    return times, speeds, None if math.isnan(start) else start
