"""Sensing: the laser line sensor (the paper's Eq. 1-8), its profiles, the stripe by ray casting
(Embree kernels) and the noise models.

Modules are imported on demand: ``seamtrack.sensing.profiles`` needs neither Embree nor numba.
"""
