"""Analysis of results: the run report (dynamic factor, bearing-force peak-to-peak, order
lines; :mod:`~orchestrator.analysis.metrics`), the order spectrum every figure draws, in peak
amplitude (:mod:`~orchestrator.analysis.spectrum`), and the linearised system at X0 (damped
modes, critical speeds, Campbell diagram).
"""
