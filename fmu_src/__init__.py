"""pythonfmu slave classes exposing the physics as FMI 2.0 co-simulation FMUs."""

from bearing_fmu import numba_cache

numba_cache.install()  # before any kernel is defined: numba's cache per version of the code
