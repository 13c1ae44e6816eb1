"""pythonfmu slave shared by every bearing FMU: the contract's variables around one model.

Nothing physical happens here: the slave converts global <-> local frame, calls the model of
:mod:`bearing_fmu` and exposes force, Kb and Cb. Outputs are computed lazily in the getters, so
they reflect new inputs without a doStep (the master reads them inside a step). The model is
(re)built whenever a parameter changes.

The linear FMU runs the hybrid model until it leaves initialisation mode and then freezes the
8 coefficients at the journal state it has then (the static position the master found):
the paper's linear analysis (Sec. 3.3) with the same variables as every other bearing FMU.
"""

from __future__ import annotations

import math

import numpy as np
from pythonfmu import Fmi2Slave
from pythonfmu.enums import Fmi2Status

from bearing_fmu import BearingData, model_class
from bearing_fmu.frames import LocalFrame
from bearing_fmu.linear import LinearBearing
from fmu_src.contract import (
    BEARING_VARIABLES,
    DAMPING_NAMES,
    FORCE_NAMES,
    STIFFNESS_NAMES,
)
from fmu_src.slave_support import (
    describe_exception,
    pin_namespace,
    register_contract_variable,
    release_python_state_at_exit,
)

__all__ = ["BearingSlave", "pin_namespace"]


class BearingSlave(Fmi2Slave):
    """Base of the bearing FMUs; subclasses set ``model_name`` (a key of bearing_fmu.MODELS)."""

    model_name = "hybrid"
    author = "gear-shaft-bearing contributors"
    license = "MIT"

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.description = (
            f"Journal bearing ({self.model_name} model): film force and its stiffness and "
            "damping at the journal state, global frame, SI units (Baguet & Jacquenot 2010)."
        )
        self._values = {v.name: v.start for v in BEARING_VARIABLES}
        self._dirty_model = True
        self._dirty_outputs = True
        self._model = None
        self._frame = None
        self._frozen = None  # LinearBearing of the linear FMU after initialisation
        self._failed = False
        release_python_state_at_exit(self.resources, type(self).__name__)
        for v in BEARING_VARIABLES:
            self._register(v)

    # --- FMI plumbing ------------------------------------------------------------------------
    def _register(self, v):
        setter = None
        if v.causality in ("parameter", "input"):
            setter = self._setter(v.name, model=v.causality == "parameter")
        register_contract_variable(self, v, self._getter(v.name), setter)

    def _getter(self, name):
        if any(name == v.name and v.causality == "output" for v in BEARING_VARIABLES):
            def get():
                if self._dirty_outputs:
                    self._update()
                return self._values[name]
        else:
            def get():
                return self._values[name]
        return get

    def _setter(self, name, model):
        def set_(value):
            if self._values[name] != value:
                self._values[name] = value
                self._dirty_outputs = True
                if model:
                    self._dirty_model = True
        return set_

    # --- physics ------------------------------------------------------------------------------
    def _build_model(self):
        v = self._values
        bearing = BearingData(v["D"], v["L"], v["C"], v["mu"])
        name = "hybrid" if self.model_name == "linear" else self.model_name
        cls = model_class(name)
        if name == "hybrid":
            model = cls(bearing, n=int(v["n_theta"]))
        elif name == "fd":
            model = cls(bearing, n_theta=int(v["n_theta"]), n_xi=int(v["n_xi"]))
        elif name == "lumped":
            model = cls(bearing, v["k_lumped"], v["c_lumped"])
        else:
            model = cls(bearing)
        self._model = model
        self._frame = LocalFrame(v["frame_angle"], int(v["rotation_sign"]))
        self._dirty_model = False

    def _local_state(self):
        v = self._values
        x, y = self._frame.to_local((v["s"], v["t"]))
        xd, yd = self._frame.to_local((v["s_dot"], v["t_dot"]))
        return x, y, xd, yd

    def _update(self):
        """Evaluate the law at the current inputs; never raises into the FMI layer.

        A Python exception in a pythonfmu getter is fatal for the instance (and its host may
        crash on the next call), so a bad state (eccentricity >= 1, bad parameters) is logged
        with status error, the outputs become NaN and the next doStep returns discard.
        """
        try:
            self._evaluate()
            self._failed = False
        except Exception as exc:  # anything raised here would be fatal for the host
            self._failed = True
            self.log(f"{self.instance_name}: {describe_exception(exc)}", Fmi2Status.error)
            for name in FORCE_NAMES + STIFFNESS_NAMES + DAMPING_NAMES:
                self._values[name] = math.nan
        self._dirty_outputs = False

    def _evaluate(self):
        if self._dirty_model:
            self._build_model()
        v = self._values
        x, y, xd, yd = self._local_state()
        law = self._frozen if self._frozen is not None else self._model
        r = law.evaluate(x, y, xd, yd, v["omega"])
        fr = self._frame
        force = fr.to_global(r.force)
        k = fr.matrix_to_global(r.stiffness)
        c = fr.matrix_to_global(r.damping)
        for name, val in zip(FORCE_NAMES, force, strict=True):
            v[name] = float(val)
        for name, val in zip(STIFFNESS_NAMES, k.ravel(), strict=True):
            v[name] = float(val)
        for name, val in zip(DAMPING_NAMES, c.ravel(), strict=True):
            v[name] = float(val)
        v["eccentricity"] = math.hypot(x, y) / v["C"]
        v["n_solves"] = int(v["n_solves"]) + 1

    # --- FMI life cycle -----------------------------------------------------------------------
    def exit_initialization_mode(self):
        if self.model_name != "linear":
            return
        try:
            if self._dirty_model:
                self._build_model()
            x, y, _, _ = self._local_state()
            self._frozen = LinearBearing.linearise(self._model, x, y, self._values["omega"])
        except Exception as exc:  # anything raised here would be fatal for the host
            self._failed = True
            self.log(f"{self.instance_name}: cannot linearise: {describe_exception(exc)}",
                     Fmi2Status.error)
        self._dirty_outputs = True

    def do_step(self, current_time, step_size):
        """Algebraic slave: outputs follow the inputs in the getters; discard after a failure."""
        if self._dirty_outputs:
            self._update()
        return not self._failed

    # state: the variables (pythonfmu's default) plus the frozen linear law
    def _get_fmu_state(self):
        state = {"values": dict(self._values)}
        if self._frozen is not None:
            fz = self._frozen
            state["frozen"] = [fz.position0.tolist(), fz.force0.tolist(),
                               fz.stiffness.tolist(), fz.damping.tolist(), fz.omega]
        return state

    def _set_fmu_state(self, state):
        self._values = dict(state["values"])
        self._dirty_model = True
        self._dirty_outputs = True
        self._build_model()
        if "frozen" in state:
            p0, f0, k, c, om = state["frozen"]
            self._frozen = LinearBearing(self._model.bearing, p0, f0, np.array(k), np.array(c),
                                         om)
        else:
            self._frozen = None
