"""The hybrid method (paper Sec. 2.2.2): :class:`~bearing_fmu.hybrid.model.HybridBearing`,
its axial pressure shape (:mod:`~bearing_fmu.hybrid.axial`) and its compiled kernels (the Ritz
matrices, the complementarity problem, the analytic Jacobians; private to this package).
"""
