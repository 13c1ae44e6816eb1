"""Gear-shaft structural model: Timoshenko shafts, gear mesh element, Newmark step."""

from bearing_fmu import numba_cache

numba_cache.install()  # before any kernel is defined: numba's cache per version of the code
