"""A run's life cycle: the runner (static solution, transient, report), the checks before
the transient, the results file (HDF5, written as the run goes, resumable) and its name.
"""
