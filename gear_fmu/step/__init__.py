"""The structure's time step (paper Eq. 11-16): Newmark's scheme
(:mod:`~gear_fmu.step.newmark`), the condensation onto the coupled DOFs, the contact loop, the
step's assembly and the whole step as one compiled call (:mod:`~gear_fmu.step.kernel`).
"""
