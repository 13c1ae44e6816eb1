"""Studies built on runs and sweeps: the reproduction of the paper's section 4
(:mod:`~orchestrator.studies.reproduce`), the drivetrain sensitivity study
(:mod:`~orchestrator.studies.drivetrain`) and the accuracy of non-iterating FMI masters
against the step (:mod:`~orchestrator.studies.coupling_accuracy`).
"""
