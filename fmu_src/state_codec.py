"""Saved states as plain numbers: a flat mapping name -> numpy array in an npz archive.

Every state this package writes to bytes (the master's resume checkpoint in a results file,
an FMU's fmi2SerializeFMUstate) is such a mapping, tagged with the format version
(:data:`FORMAT_VERSION`) and a kind (what the state is of, e.g. ``"gsb.master_checkpoint"``).
A results file or a serialised FMU state may come from someone else: reading one must never
run code, so nothing here is a pickle, and :func:`decode` refuses anything but this format.

The archive is numpy's npz (a zip of ``.npy`` members, stored, not compressed): ``np.load``
with ``allow_pickle=False`` reads it, and so does any npz reader. Allowed arrays
(:data:`DTYPES`): float64, int64, bool, uint8 (an opaque byte string, such as another FMU's
own serialised state) and fixed-width text, little-endian, any shape. Names are paths
``a/b/c`` (:func:`nest` prefixes a part's names); ``__format_version__`` and ``__kind__`` are
the archive's own. The bytes depend only on the arrays (fixed member dates), so a state
encodes to the same bytes each time.

:func:`decode` checks, before any array is read, that the bytes are such an archive (a pickle
is named as one), that its members are ``.npy`` arrays of allowed dtypes whose sizes match
their headers (:data:`MAX_BYTES` in all), then the version and the kind; what a state must
contain is checked by its reader through :class:`StateArrays` (missing entry, dtype, shape,
unexpected entries). Every refusal is a :class:`StateFormatError` naming the state and what is
wrong.

Only numpy and the standard library are imported: an FMU's slaves use this module.

>>> blob = encode("demo", {"x": np.arange(3.0), "n": 4, "ok": True})
>>> s = decode(blob, "demo")
>>> s.array("x", "float64", (3,)).tolist(), s.int("n"), s.bool("ok")
([0.0, 1.0, 2.0], 4, True)
>>> try:
...     decode(blob, "other")
... except StateFormatError as exc:
...     print(exc)
the state is a 'demo' state, not a 'other' state
"""

from __future__ import annotations

import io
import math
import zipfile

import numpy as np
from numpy.lib import format as npy

__all__ = ["DTYPES", "FORMAT_VERSION", "MAX_BYTES", "StateArrays", "StateFormatError",
           "decode", "encode", "nest"]

#: version of the layout of the archive; a reader refuses any other
FORMAT_VERSION = 1
#: largest archive (and sum of its arrays) :func:`decode` reads [bytes]
MAX_BYTES = 1 << 28
#: the dtypes an array may have, by the name the readers use
DTYPES = {"float64": np.dtype("<f8"), "int64": np.dtype("<i8"), "bool": np.dtype("|b1"),
          "uint8": np.dtype("|u1")}
_VERSION_KEY = "__format_version__"
_KIND_KEY = "__kind__"
#: stored zip members carry this date: the bytes depend on the content only
_DATE = (1980, 1, 1, 0, 0, 0)
_ZIP = b"PK\x03\x04"


class StateFormatError(ValueError):
    """Bytes or arrays that are not a state of the expected format, version, kind or layout
    (the message names the state and what is wrong)."""


def _dtype_name(dtype: np.dtype) -> str | None:
    """The name in :data:`DTYPES` (or ``"str"`` for fixed-width text) of an allowed dtype."""
    for name, allowed in DTYPES.items():
        if dtype == allowed:
            return name
    if dtype.kind == "U" and dtype.str[0] in "<|":
        return "str"
    return None


def _check_name(name) -> str:
    if not isinstance(name, str) or not name or name.startswith("__") or "\\" in name or any(
            part in ("", ".", "..") for part in name.split("/")):
        raise ValueError(f"state entry name {name!r}: need a non-empty path a/b/c without "
                         "empty, '.' or '..' parts, not starting with '__'")
    return name


def nest(prefix: str, arrays: dict) -> dict:
    """``arrays`` with every name under ``prefix/`` (a part of a larger state)."""
    return {f"{prefix}/{name}": value for name, value in arrays.items()}


def _as_allowed(name: str, value) -> np.ndarray:
    arr = np.asarray(value)
    if arr.dtype.str[0] == ">":  # the same values, little-endian
        arr = arr.astype(arr.dtype.newbyteorder("<"))
    if _dtype_name(arr.dtype) is None:
        raise TypeError(f"state entry {name!r}: dtype {arr.dtype} is not allowed (float64, "
                        "int64, bool, uint8 or text)")
    return arr


def encode(kind: str, arrays: dict) -> bytes:
    """The npz bytes of a state: ``arrays`` (name -> array or Python number, bool, str) with
    the format version and ``kind``."""
    members = {_VERSION_KEY: np.array(FORMAT_VERSION, dtype="<i8"),
               _KIND_KEY: np.array(str(kind))}
    for name, value in arrays.items():
        members[_check_name(name)] = _as_allowed(name, value)
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", zipfile.ZIP_STORED) as zf:
        for name, arr in members.items():
            info = zipfile.ZipInfo(name + ".npy", date_time=_DATE)
            with zf.open(info, "w", force_zip64=True) as fh:
                npy.write_array(fh, arr, allow_pickle=False)
    return buf.getvalue()


def _refuse_start(data: bytes, what: str) -> None:
    """A clear error for bytes that are not a zip archive (a pickle of protocol 2 or later
    named as one; any other is refused as not this format)."""
    if data[:1] == b"\x80" and data[1:2] and 2 <= data[1] <= 5:
        raise StateFormatError(f"{what} is a Python pickle (protocol {data[1]}): refused, "
                               "loading a pickle can run any code")
    raise StateFormatError(f"{what} is not a saved state of this format (an npz archive of "
                           f"numeric arrays): it starts with {data[:8]!r}")


def _read_members(data: bytes, what: str) -> dict:
    """The arrays of an npz archive, each checked before it is read."""
    try:
        zf = zipfile.ZipFile(io.BytesIO(data))
        infos = zf.infolist()
    except (zipfile.BadZipFile, OSError, ValueError, EOFError) as exc:
        raise StateFormatError(f"{what} is not a readable npz archive: {exc}") from None
    total = sum(info.file_size for info in infos)
    if total > MAX_BYTES:
        raise StateFormatError(f"{what} holds {total} bytes of arrays, more than the "
                               f"{MAX_BYTES} a state may")
    out = {}
    with zf:
        for info in infos:
            member = info.filename
            if not member.endswith(".npy") or info.is_dir():
                raise StateFormatError(f"{what} has the member {member!r}, not an array (.npy)")
            name = member[:-4]
            if name in out:
                raise StateFormatError(f"{what} has the entry {name!r} twice")
            try:
                with zf.open(info) as fh:
                    version = npy.read_magic(fh)
                    if version not in ((1, 0), (2, 0)):
                        raise StateFormatError(f"{what}: entry {name!r} is an .npy array of "
                                               f"version {version}; a state uses 1.0 or 2.0")
                    reader = (npy.read_array_header_1_0 if version == (1, 0)
                              else npy.read_array_header_2_0)
                    shape, fortran, dtype = reader(fh)
                    if _dtype_name(dtype) is None:
                        raise StateFormatError(
                            f"{what}: entry {name!r} has dtype {dtype}; a state holds only "
                            "float64, int64, bool, uint8 and text arrays")
                    nbytes = math.prod(shape) * dtype.itemsize
                    if fh.tell() + nbytes != info.file_size:
                        raise StateFormatError(
                            f"{what}: entry {name!r} holds {info.file_size - fh.tell()} bytes "
                            f"of data, its header says {nbytes} (shape {shape})")
                    raw = fh.read(nbytes)
            except StateFormatError:
                raise
            except (ValueError, OSError, EOFError, zipfile.BadZipFile) as exc:
                raise StateFormatError(f"{what}: entry {name!r} is not a readable array: "
                                       f"{exc}") from None
            arr = np.frombuffer(raw, dtype=dtype).reshape(shape, order="F" if fortran else "C")
            out[name] = np.array(arr, order="C")  # writable, C order
    return out


def decode(data, kind: str, what: str = "the state") -> StateArrays:
    """The arrays of :func:`encode` bytes of ``kind``; :class:`StateFormatError` (its message
    starts with ``what``) for anything else (module docstring)."""
    if isinstance(data, np.ndarray):
        data = data.tobytes()
    if not isinstance(data, (bytes, bytearray, memoryview)):
        raise StateFormatError(f"{what} is a {type(data).__name__}, not bytes")
    data = bytes(data)
    if len(data) > MAX_BYTES:
        raise StateFormatError(f"{what} has {len(data)} bytes, more than the {MAX_BYTES} a "
                               "state may")
    if not data.startswith(_ZIP):
        _refuse_start(data, what)
    arrays = _read_members(data, what)
    version = arrays.pop(_VERSION_KEY, None)
    if version is None or version.dtype != DTYPES["int64"] or version.shape != ():
        raise StateFormatError(f"{what} has no format version (an npz archive, but not a "
                               "state written by this package)")
    if int(version) != FORMAT_VERSION:
        raise StateFormatError(f"{what} has format version {int(version)}; this version of "
                               f"the package reads version {FORMAT_VERSION}")
    found = arrays.pop(_KIND_KEY, None)
    if found is None or found.dtype.kind != "U" or found.shape != ():
        raise StateFormatError(f"{what} has no kind tag")
    if str(found) != kind:
        raise StateFormatError(f"{what} is a {str(found)!r} state, not a {kind!r} state")
    for name in arrays:
        try:
            _check_name(name)
        except ValueError as exc:
            raise StateFormatError(f"{what}: {exc}") from None
    return StateArrays(arrays, what)


class StateArrays:
    """The arrays of a state, read by name with the dtype and shape the reader expects.

    Parameters
    ----------
    arrays : dict
        name -> numpy array (a decoded state, or one held in memory).
    what : str
        The state, for messages (``"the checkpoint"``).

    A view of a part (:meth:`sub`) shares the record of what was read, so that
    :meth:`check_all_read` on the whole state names entries no reader used.
    """

    def __init__(self, arrays: dict, what: str = "the state", _prefix: str = "",
                 _read: set | None = None):
        self._arrays = arrays
        self.what = what
        self._prefix = _prefix
        self._read = set() if _read is None else _read

    def sub(self, prefix: str) -> StateArrays:
        """The part under ``prefix/`` (names relative to it)."""
        return StateArrays(self._arrays, self.what, f"{self._prefix}{prefix}/", self._read)

    def names(self) -> list[str]:
        """The names of this part's entries (relative, sorted)."""
        n = len(self._prefix)
        return sorted(k[n:] for k in self._arrays if k.startswith(self._prefix))

    def part(self, prefix: str) -> dict:
        """The entries under ``prefix/`` as a dict (relative names), taken as read: a part
        its reader checks later, against the object it restores (``StateArrays(part)``)."""
        start = f"{self._prefix}{prefix}/"
        out = {k[len(start):]: v for k, v in self._arrays.items() if k.startswith(start)}
        self._read.update(start + k for k in out)
        return out

    def has(self, name: str) -> bool:
        """Whether the entry exists (an optional part: absent stands for None)."""
        return f"{self._prefix}{name}" in self._arrays

    def has_part(self, prefix: str) -> bool:
        """Whether any entry is under ``prefix/``."""
        return bool(self.sub(prefix).names())

    def array(self, name: str, dtype: str, shape: tuple | None = None) -> np.ndarray:
        """The entry ``name`` (a copy) of dtype ``dtype`` (a key of :data:`DTYPES` or
        ``"str"``) and ``shape`` (None: any; an entry None in the tuple: any length)."""
        full = f"{self._prefix}{name}"
        arr = self._arrays.get(full)
        if arr is None:
            raise StateFormatError(f"{self.what} lacks the entry {full!r}")
        arr = np.asarray(arr)
        found = _dtype_name(arr.dtype)
        if found != dtype:
            raise StateFormatError(f"{self.what}: entry {full!r} has dtype "
                                   f"{found or arr.dtype}, expected {dtype}")
        if shape is not None and (len(shape) != arr.ndim or any(
                want is not None and want != got
                for want, got in zip(shape, arr.shape, strict=True))):
            want = tuple("any" if s is None else s for s in shape)
            raise StateFormatError(f"{self.what}: entry {full!r} has shape {arr.shape}, "
                                   f"expected {want}")
        self._read.add(full)
        return np.array(arr, copy=True)

    def float(self, name: str) -> float:
        """A float64 scalar entry as a Python float (the same bits)."""
        return float(self.array(name, "float64", ()))

    def int(self, name: str) -> int:
        return int(self.array(name, "int64", ()))

    def bool(self, name: str) -> bool:
        return bool(self.array(name, "bool", ()))

    def text(self, name: str) -> str:
        return str(self.array(name, "str", ()))

    def bytes(self, name: str) -> bytes:
        """A uint8 vector entry as bytes (an opaque blob)."""
        return self.array(name, "uint8", (None,)).tobytes()

    def value(self, name: str):
        """An entry of any dtype but uint8 as Python values: a number, flag or text for a 0-d
        entry, nested lists of them otherwise (a value whose owner checks it)."""
        full = f"{self._prefix}{name}"
        arr = self._arrays.get(full)
        if arr is None:
            raise StateFormatError(f"{self.what} lacks the entry {full!r}")
        kind = _dtype_name(np.asarray(arr).dtype)
        if kind in ("uint8", None):
            raise StateFormatError(f"{self.what}: entry {full!r} has dtype {arr.dtype}, "
                                   "expected numbers, flags or text")
        return self.array(name, kind).tolist()

    def check_all_read(self) -> None:
        """Refuse entries of this part that no reader used (a state of another layout)."""
        extra = [k for k in self._arrays if k.startswith(self._prefix) and k not in self._read]
        if extra:
            shown = ", ".join(repr(k) for k in sorted(extra)[:5])
            more = f" and {len(extra) - 5} more" if len(extra) > 5 else ""
            raise StateFormatError(f"{self.what} has unexpected entries {shown}{more}")
