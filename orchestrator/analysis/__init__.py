"""Analysis of results: the run report (dynamic factor, bearing-force peak-to-peak, order
lines) and the linearised system at X0 (damped modes, critical speeds, Campbell diagram).
"""
