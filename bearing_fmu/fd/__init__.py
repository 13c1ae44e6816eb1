"""The finite-difference/multigrid Reynolds solver, the accuracy reference (Table 4 case 4):
:class:`~bearing_fmu.fd.model.FiniteDifferenceBearing` and its direct reference solver
(:mod:`~bearing_fmu.fd.reference`); the grid and the kernels are private to this package.
"""
