"""What every pythonfmu slave of this package shares: toolchain workarounds, contract plumbing.

* :func:`pin_namespace` and :func:`release_python_state_at_exit` work around two pythonfmu
  0.7.0 defects (README, "pythonfmu notes"); every slave script / slave class calls them.
* :func:`register_contract_variable` registers one :class:`fmu_src.contract.FmiVar` with
  pythonfmu (causality, variability, type), so the variable lists stay in
  :mod:`fmu_src.contract` and the slaves only supply getters and setters.
* :func:`describe_exception` formats an exception for the FMU log: a Python exception that
  escapes a pythonfmu callback is fatal for the instance (and the host may crash on its next
  call), so slaves catch everything, log it with status error and report a non-OK status.
"""

from __future__ import annotations

from pythonfmu import Boolean, Fmi2Causality, Fmi2Variability, Integer, Real, String

__all__ = [
    "describe_exception",
    "pin_namespace",
    "register_contract_variable",
    "release_python_state_at_exit",
]

_PINNED: list = []


def pin_namespace(namespace: dict, count: int = 10_000) -> None:
    """Hold ``count`` extra references to a slave script's module namespace.

    pythonfmu 0.7.0 drops one reference to the slave module's ``__dict__`` each time an
    instance is created (seen with ``sys.getrefcount``: the second instantiation of the same FMU
    in one process frees the namespace, then fails with "module has no attribute" or corrupts
    the heap). Every slave script calls this once at import; 10,000 instances per process are
    then safe.
    """
    _PINNED.extend([namespace] * count)


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
    handle = ctypes.CDLL(str(lib))
    atexit.register(handle.finalizePythonInterpreter)


_CAUSALITY = {
    "parameter": Fmi2Causality.parameter,
    "calculatedParameter": Fmi2Causality.calculatedParameter,
    "input": Fmi2Causality.input,
    "output": Fmi2Causality.output,
}
_TYPE = {"Real": Real, "Integer": Integer, "Boolean": Boolean, "String": String}


def register_contract_variable(slave, v, getter, setter=None) -> None:
    """Register contract variable ``v`` (:class:`fmu_src.contract.FmiVar`) on ``slave``.

    Parameters and calculated parameters are ``fixed``; inputs are continuous; outputs are
    continuous (Real) or discrete (other types). ``setter`` is required for parameters and
    inputs, ignored otherwise.
    """
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
        kw["setter"] = setter
    slave.register_variable(_TYPE[v.type](v.name, **kw))


def describe_exception(exc: BaseException) -> str:
    """``"TypeName: message"`` (the first line of a multi-line message is kept whole)."""
    return f"{type(exc).__name__}: {exc}"
