"""FMU slave script: journal bearing, fd model (variables: fmu_src.contract)."""

from fmu_src.bearing_slave import BearingSlave, pin_namespace


class BearingFd(BearingSlave):
    model_name = "fd"


pin_namespace(globals())  # pythonfmu 0.7.0 workaround, see pin_namespace
