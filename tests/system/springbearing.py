"""A bearing FMU of one's own, with the minimal contract only (tests/system/test_fmu_system.py
builds it with pythonfmu): the journal state in, the film force out (global frame); here an
isotropic spring and damper, the built-in lumped model."""

from pythonfmu import Fmi2Causality, Fmi2Slave, Fmi2Variability, Real


class SpringBearing(Fmi2Slave):
    author = "a user"
    description = "isotropic spring and damper: F = -k X - c Xdot (global frame, SI)"

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.lumped_stiffness = 1e8
        self.lumped_damping = 0.0
        self.s = self.t = self.s_dot = self.t_dot = 0.0
        for name in ("lumped_stiffness", "lumped_damping"):
            self.register_variable(Real(name, causality=Fmi2Causality.parameter,
                                        variability=Fmi2Variability.fixed))
        for name in ("s", "t", "s_dot", "t_dot"):
            self.register_variable(Real(name, causality=Fmi2Causality.input))
        self.register_variable(Real("F_s", causality=Fmi2Causality.output, getter=lambda: (
            -self.lumped_stiffness * self.s - self.lumped_damping * self.s_dot)))
        self.register_variable(Real("F_t", causality=Fmi2Causality.output, getter=lambda: (
            -self.lumped_stiffness * self.t - self.lumped_damping * self.t_dot)))

    def do_step(self, current_time, step_size):
        return True
