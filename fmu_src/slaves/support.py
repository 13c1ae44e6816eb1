"""What every pythonfmu slave of this package shares: the contract, statuses, workarounds.

* :class:`ContractSlave`: registers the variables of a contract (:mod:`fmu_src.contract`) and
  serves the FMI get/set calls. A value a variable refuses (:meth:`FmiVar.check
  <fmu_src.contract.FmiVar.check>`, or a setter raising :class:`~fmu_src.contract.ValueRefused`)
  is logged and reported as fmi2Error by the call that set it; an output that cannot be
  computed (a getter calls :meth:`ContractSlave.output_failed`) makes the read return fmi2Error.
  Statuses need the patched library of :mod:`fmu_src.build.native` (it sets
  ``_fmi_status_protocol``); with pythonfmu's own library a refused value is only logged and
  a failed output reads NaN.
* :func:`pin_namespace` and :func:`release_python_state_at_exit` work around two defects of
  pythonfmu 0.7.0's own library (README, "pythonfmu notes"); with the patched library they are
  harmless.
* :func:`describe_exception` formats an exception for the FMU log: a Python exception that
  escapes a pythonfmu callback is fatal for the instance, so slaves catch everything, log it
  and report a non-OK status.
"""

from __future__ import annotations

import numpy as np
from pythonfmu import Boolean, Fmi2Causality, Fmi2Slave, Fmi2Variability, Integer, Real, String
from pythonfmu.enums import Fmi2Status

from bearing_fmu.blas_threads import limit_for_good
from fmu_src.contract import ValueRefused, parameter_field
from fmu_src.state_codec import StateArrays, decode, encode

__all__ = [
    "FMI_ERROR",
    "ContractSlave",
    "case_parameter",
    "describe_exception",
    "pin_namespace",
    "release_python_state_at_exit",
]

FMI_OK, FMI_WARNING, FMI_DISCARD, FMI_ERROR = 0, 1, 2, 3


def pin_namespace(namespace: dict) -> None:
    """Add one reference to a slave script's module namespace, owned by no object.

    pythonfmu 0.7.0's library runs the slave script again at every instantiation, in the
    module's namespace, then drops one reference to that namespace (a borrowed reference
    released; the patched library keeps it): without a reference to make up for it, the
    second instantiation of the same FMU in one process frees the namespace, then fails with
    "module has no attribute" or corrupts the heap. Every slave script calls this at its end,
    so that each run of it adds the reference that run's instantiation drops.

    The reference is a count, not an object kept in a list: an instantiation then costs no
    memory here, whichever library runs the script (with the patched one the namespace, which
    lives as long as its module in ``sys.modules`` anyway, is only never freed).
    """
    import ctypes

    ctypes.pythonapi.Py_IncRef(ctypes.py_object(namespace))


_EXIT_FIXED: set = set()


def release_python_state_at_exit(resources: str | None, model_identifier: str) -> None:
    """Let pythonfmu 0.7.0's library drop its Python state before the C exit handlers run.

    Its shared library keeps a static ``shared_ptr`` that the C++ exit handlers destroy before
    the library's destructor ``finalizePythonInterpreter`` resets it again: a use-after-free
    (valgrind) that corrupts the heap and often aborts a Python host at exit, after all results
    ("corrupted double-linked list"). In a Python host, calling ``finalizePythonInterpreter``
    from a Python ``atexit`` handler (which runs before the C exit handlers) resets the pointer
    while it is alive, and the late call becomes a no-op. Not done when pythonfmu itself
    started the interpreter (a C host): there Python's exit runs on pythonfmu's own thread.
    (The patched library never destroys that state, and its ``finalizePythonInterpreter`` does
    nothing.)
    """
    import atexit
    import ctypes
    import sys
    from pathlib import Path

    if not sys.platform.startswith("linux") or resources is None:
        return
    if not sys.argv or not sys.argv[0] or Path(sys.executable).name == "PythonFMU":
        return  # embedded by pythonfmu (C host), or an interactive session: leave it alone
    lib = Path(resources).parent / "binaries" / "linux64" / f"{model_identifier}.so"
    if not lib.is_file() or str(lib) in _EXIT_FIXED:
        return
    _EXIT_FIXED.add(str(lib))
    finalize = getattr(ctypes.CDLL(str(lib)), "finalizePythonInterpreter", None)
    if finalize is not None:  # not behind this package's loader (the patched library)
        atexit.register(finalize)


_CAUSALITY = {
    "parameter": Fmi2Causality.parameter,
    "calculatedParameter": Fmi2Causality.calculatedParameter,
    "input": Fmi2Causality.input,
    "output": Fmi2Causality.output,
}
_TYPE = {"Real": Real, "Integer": Integer, "Boolean": Boolean, "String": String}
_CONVERT = {Real: float, Integer: int, Boolean: bool, String: str}


def describe_exception(exc: BaseException) -> str:
    """``"TypeName: message"`` (the first line of a multi-line message is kept whole)."""
    return f"{type(exc).__name__}: {exc}"


class ContractSlave(Fmi2Slave):
    """Base of this package's slaves (module docstring)."""

    author = "gear-shaft-bearing contributors"
    license = "MIT"
    #: set to True by the patched FMU library: statuses can be returned (fmu_src.build.native)
    _fmi_status_protocol = False

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        limit_for_good()  # hosts call FMUs from several threads (bearing_fmu.blas_threads)
        self._read_status = FMI_OK
        self._by_kind = {}  # {variable type: {value reference: variable}}, see _accessors
        release_python_state_at_exit(self.resources, type(self).__name__)

    def _fmi_release(self) -> None:
        """Break the reference cycles the slave is in; the patched library
        (:mod:`fmu_src.build.native`) calls this just before it drops the slave
        (fmi2FreeInstance, fmi2Reset).

        The getters and setters of the variables, and the bound methods handed to helpers,
        refer back to the slave: dropped as it is, the slave and all it holds (the gear-shaft
        FMU's matrices, some MiB) would wait for Python's next full garbage collection, often
        hundreds of instances later. Emptying its attributes breaks every cycle through it, so
        it is freed at once. The slave is never called again.
        """
        self.__dict__.clear()

    # --- registration -------------------------------------------------------------------------
    def register_contract_variable(self, v, getter, setter=None) -> None:
        """Register contract variable ``v`` (:class:`fmu_src.contract.FmiVar`): parameters and
        calculated parameters are ``fixed``; inputs continuous; outputs continuous (Real) or
        discrete. The setter, required for parameters and inputs, is called only with values
        ``v.check`` accepts (converted to the variable's type)."""
        kw = dict(causality=_CAUSALITY[v.causality], description=v.description, getter=getter)
        if v.causality in ("parameter", "calculatedParameter"):
            kw["variability"] = Fmi2Variability.fixed
        elif v.causality == "input" or v.type == "Real":
            kw["variability"] = Fmi2Variability.continuous
        else:
            kw["variability"] = Fmi2Variability.discrete
        if v.causality in ("parameter", "input"):
            if setter is None:
                raise ValueError(f"{v.name}: a {v.causality} needs a setter")

            def checked(value, v=v, setter=setter):
                v.check(value)
                setter(value)
            kw["setter"] = checked
        self.register_variable(_TYPE[v.type](v.name, **kw))

    # --- statuses -----------------------------------------------------------------------------
    def refuse(self, exc: BaseException) -> int:
        """Log a refused value; the status its setter call returns (fmi2Error)."""
        self.log(f"{self.instance_name}: {exc}", Fmi2Status.error)
        return FMI_ERROR

    def output_failed(self, what: str, exc: BaseException) -> str:
        """Log why outputs cannot be computed and make the current read return fmi2Error."""
        msg = f"{self.instance_name}: {what}: {describe_exception(exc)}"
        self.log(msg, Fmi2Status.error)
        self._read_status = FMI_ERROR
        return msg

    def _accessors(self, kind) -> dict:
        """``{value reference: variable}`` of the variables of ``kind`` (built on first use:
        the variables are all registered by then)."""
        table = self._by_kind.get(kind)
        if table is None:
            table = self._by_kind[kind] = {vr: var for vr, var in self.vars.items()
                                           if isinstance(var, kind)}
        return table

    def _wrong_kind(self, kind, vrs):
        bad = next(vr for vr in vrs if vr not in self._accessors(kind))
        return TypeError(f"variable with valueReference={bad} is not of type {kind.__name__}")

    def _set(self, kind, vrs, values):
        status = FMI_OK
        table = self._accessors(kind)
        for vr, value in zip(vrs, values, strict=True):
            var = table.get(vr)
            if var is None:
                raise self._wrong_kind(kind, vrs)
            try:
                var.setter(value)
            except ValueRefused as exc:
                status = self.refuse(exc)
        return status or None

    def _get(self, kind, vrs):
        self._read_status = FMI_OK
        conv = _CONVERT[kind]
        table = self._accessors(kind)
        try:
            getters = [table[vr].getter for vr in vrs]
        except KeyError:
            raise self._wrong_kind(kind, vrs) from None
        return self._with_status([conv(get()) for get in getters])

    def _with_status(self, values):
        """``values``, or ``(values, status)`` after a failed output (patched library only)."""
        status, self._read_status = self._read_status, FMI_OK
        if status and self._fmi_status_protocol:
            return values, status
        return values

    def set_real(self, vrs, values):
        return self._set(Real, vrs, values)

    def set_integer(self, vrs, values):
        return self._set(Integer, vrs, values)

    def set_boolean(self, vrs, values):
        return self._set(Boolean, vrs, values)

    def set_string(self, vrs, values):
        return self._set(String, vrs, values)

    def get_real(self, vrs):
        return self._get(Real, vrs)

    def get_integer(self, vrs):
        return self._get(Integer, vrs)

    def get_boolean(self, vrs):
        return self._get(Boolean, vrs)

    def get_string(self, vrs):
        return self._get(String, vrs)

    # --- FMU state serialisation (fmi2SerializeFMUstate) ---------------------------------------
    # The library calls these two on the class. The bytes are a state of fmu_src.state_codec
    # (numeric arrays, kind _state_kind()): a state from anywhere may be deserialised without
    # running code. Bytes that are not such a state raise StateFormatError, which the patched
    # library (fmu_src.build.native) returns as fmi2Error with the message in the log, the
    # instance intact (pythonfmu's own library makes it fmi2Fatal).
    #: the kind tag of this slave's serialised states
    STATE_KIND: str = ""

    @classmethod
    def _state_kind(cls) -> str:
        """The kind tag of this slave's serialised states (:attr:`STATE_KIND`)."""
        if not cls.STATE_KIND:
            raise NotImplementedError(f"{cls.__name__} declares no STATE_KIND")
        return cls.STATE_KIND

    @classmethod
    def _state_to_arrays(cls, state) -> dict:
        """The flat arrays of a state of ``_get_fmu_state``."""
        raise NotImplementedError

    @classmethod
    def _state_from_arrays(cls, arrays: StateArrays):
        """The ``_get_fmu_state`` form of decoded arrays, checked as far as can be without
        an instance (``_set_fmu_state`` checks the rest)."""
        raise NotImplementedError

    @classmethod
    def _fmu_state_to_bytes(cls, state) -> bytes:
        return encode(cls._state_kind(), cls._state_to_arrays(state))

    @classmethod
    def _fmu_state_from_bytes(cls, state: bytes):
        arrays = decode(state, cls._state_kind(), what="the serialised FMU state")
        out = cls._state_from_arrays(arrays)
        arrays.check_all_read()
        return out


def overrides_to_arrays(overrides: dict) -> dict:
    """The case fields a slave's parameters changed ({field: value}) as the arrays
    ``overrides/<field>`` of a serialised state (:mod:`fmu_src.state_codec`)."""
    return {f"overrides/{key}": np.asarray(value) for key, value in overrides.items()}


def overrides_from_arrays(arrays: StateArrays) -> dict:
    """The {field: value} of :func:`overrides_to_arrays`, unchecked: the case checks them when
    the state is set."""
    ov = arrays.sub("overrides")
    return {key: ov.value(key) for key in ov.names()}


def case_parameter(slave, name: str, changed):
    """``(getter, setter)`` of the FMU parameter ``name``, a case field or one entry of a list
    field (:func:`fmu_src.contract.parameter_field`), for a slave that holds its carried case in
    ``_base`` and the values set in ``_overrides`` ({case field: value}); ``changed()`` runs
    when a set changes a value (the slave rebuilds what depends on the case)."""
    key, i = parameter_field(name)

    def get():
        value = slave._overrides.get(key, slave._base[key])
        return value if i is None else value[i]

    def set_(value):
        current = slave._overrides.get(key, slave._base[key])
        new = value if i is None else [*current[:i], value, *current[i + 1:]]
        if new != current:
            slave._overrides[key] = new
            changed()
    return get, set_
