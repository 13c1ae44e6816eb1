"""FMU slave script: journal bearing, hybrid model (variables: fmu_src.contract)."""

from fmu_src.bearing_slave import BearingSlave, pin_namespace


class BearingHybrid(BearingSlave):
    model_name = "hybrid"


pin_namespace(globals())  # pythonfmu 0.7.0 workaround, see pin_namespace
