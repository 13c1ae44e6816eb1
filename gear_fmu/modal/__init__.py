"""Modal analyses of the structure: modes and the exact mean mesh stiffness
(:mod:`~gear_fmu.modal.analyses`), mode tables (:mod:`~gear_fmu.modal.modes`), the damping
models (:mod:`~gear_fmu.modal.damping`) and the damped modes with critical speeds
(:mod:`~gear_fmu.modal.damped_modes`).
"""
