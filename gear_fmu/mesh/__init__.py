"""The gear pair and its mesh (paper Sec. 2.1): the geometry (:mod:`~gear_fmu.mesh.geometry`),
the tooth stiffness per unit length (:mod:`~gear_fmu.mesh.tooth_stiffness`) and the
distributed mesh element with its contact events (:mod:`~gear_fmu.mesh.element`).
"""
