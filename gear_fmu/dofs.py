"""Degree-of-freedom conventions shared by every structural module (one source of truth).

Global frame (s, t, z) of the paper (Fig. 1): z along both shaft axes, s along the centre line
from the pinion centre O1 to the gear centre O2, t = z x s.

Every finite-element node carries six DOFs, in this order:

=====  ===========  ==================================================  ====
index  name         meaning                                             unit
=====  ===========  ==================================================  ====
0      ``u``        translation along s                                  m
1      ``v``        translation along t                                  m
2      ``w``        translation along z (axial)                          m
3      ``phi``      rotation about s (bending in the t-z plane)          rad
4      ``psi``      rotation about t (bending in the s-z plane)          rad
5      ``theta``    rotation about z (torsion; small, on top of the      rad
                    rigid-body rotation of the shaft)
=====  ===========  ==================================================  ====

Global DOF number of (node n, local index i) is ``6 * n + i``.
"""

DOF_PER_NODE = 6
U, V, W, PHI, PSI, THETA = range(DOF_PER_NODE)
DOF_NAMES = ("u", "v", "w", "phi", "psi", "theta")
DOF_UNITS = ("m", "m", "m", "rad", "rad", "rad")


def dof(node: int, local: int) -> int:
    """Global DOF index of local DOF ``local`` (0..5) at node ``node``."""
    return DOF_PER_NODE * node + local
