"""FMU slave script: journal bearing, lumped model (variables: fmu_src.contract)."""

from fmu_src.bearing_slave import BearingSlave, pin_namespace


class BearingLumped(BearingSlave):
    model_name = "lumped"


pin_namespace(globals())  # pythonfmu 0.7.0 workaround, see pin_namespace
