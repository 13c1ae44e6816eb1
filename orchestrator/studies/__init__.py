"""Studies built on runs and sweeps: the reproduction of the paper's section 4
(:mod:`~orchestrator.studies.reproduce`) and the drivetrain sensitivity study
(:mod:`~orchestrator.studies.drivetrain`).
"""
