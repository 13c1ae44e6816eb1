"""Tools that build and document the FMUs, never carried by one: the FMU builder, the native
layer (pythonfmu's library with this project's patches), the SSP writer and the generator of
``docs/fmu-variables.md``.
"""
