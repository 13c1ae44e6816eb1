"""FMU slave script: journal bearing, linear model (variables: fmu_src.contract)."""

from fmu_src.bearing_slave import BearingSlave, pin_namespace


class BearingLinear(BearingSlave):
    model_name = "linear"


pin_namespace(globals())  # pythonfmu 0.7.0 workaround, see pin_namespace
