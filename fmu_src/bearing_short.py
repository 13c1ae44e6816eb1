"""FMU slave script: journal bearing, short model (variables: fmu_src.contract)."""

from fmu_src.bearing_slave import BearingSlave, pin_namespace


class BearingShort(BearingSlave):
    model_name = "short"


pin_namespace(globals())  # pythonfmu 0.7.0 workaround, see pin_namespace
