"""FMU slave script: the gear-shaft structure (variables: fmu_src.contract.GEAR_VARIABLES)."""

from fmu_src.gear_shaft_slave import GearShaftSlave
from fmu_src.slave_support import pin_namespace


class GearShaft(GearShaftSlave):
    pass


pin_namespace(globals())  # pythonfmu 0.7.0 workaround, see pin_namespace
