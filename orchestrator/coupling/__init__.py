"""Coupling: the master of the co-simulation and its two transports.

* :mod:`~orchestrator.coupling.master`: the iterative master (static solution X0, one coupled
  Newmark step converged to the case tolerance) and the interfaces it drives,
  :class:`~orchestrator.coupling.master.StructureSlave` and
  :class:`~orchestrator.coupling.master.BearingSet`;
* :mod:`~orchestrator.coupling.inprocess`: those interfaces on the physics objects directly;
* :mod:`orchestrator.coupling.fmi`: the same interfaces on FMUs through fmpy.
"""
