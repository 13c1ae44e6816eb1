"""Parametric sweeps: independent in-process runs of one case on Dask, and the sweep file
they are written to one point at a time.
"""
