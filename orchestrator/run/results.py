"""Results files: HDF5, self-describing, readable while the run writes them, never lost.

One file per run. Each channel is a dataset whose first axis is time, created resizable and
extended as the run goes. The writer flushes at least every ``flush_seconds`` (1 s) of wall
time, so a crash, a kill or a power cut loses at most about a second of steps; the file is in
HDF5's single-writer / multiple-reader mode (SWMR) while it is written, so ``read_results``,
``gsb plot`` or any HDF5 tool opening it with SWMR (``h5py.File(path, "r", swmr=True)``) can
read it during the run. Units and descriptions are attributes of each dataset; the case and the
run's settings are root attributes, numbers and numeric arrays (not JSON text), each with its
unit in ``<name>_unit``.

Resume checkpoint: at every flush the writer can store a state (bytes, from its ``checkpoint``
callable: :meth:`orchestrator.coupling.master.Master.checkpoint`, the structure's state, the
bearings' warm starts or serialised FMU states and the laws after the last row written) in the
group ``resume``. The bytes are a state of :mod:`fmu_src.state_codec`: numeric arrays (float64,
int64, bool, uint8, text) in an npz archive, never a pickle, so that resuming a file from
anyone runs no code from it; the group's attribute ``format_version`` is
:data:`fmu_src.state_codec.FORMAT_VERSION`, and :func:`read_checkpoint` refuses a file with
another (the checkpoints of older versions were pickles). Two slots (uint8 datasets: the npz
bytes, ``np.load(io.BytesIO(slot[:n].tobytes()), allow_pickle=False)`` reads them) are
written in turn and ``resume/index`` names the valid one only once its bytes are flushed, so a
kill in the middle of a checkpoint leaves the previous one intact. :func:`read_checkpoint`
returns it with the number of rows it belongs to.

>>> import tempfile, os, numpy as np
>>> path = os.path.join(tempfile.mkdtemp(), "r.h5")
>>> with ResultsWriter(path, {"x": ((2,), "m", "journal position")}) as w:
...     for k in range(10):
...         w.append(time=k * 1e-3, x=np.array([k, -k]))
>>> read_results(path)["x"].shape
(10, 2)
"""

from __future__ import annotations

import json
import os
import socket
import time
import warnings
from pathlib import Path

import numpy as np

from fmu_src.state_codec import FORMAT_VERSION, StateFormatError
from orchestrator.run.channels import DESCRIPTIONS, UNITS, dims

__all__ = ["OlderFileWarning", "ResultsWriter", "add_attributes", "attribute_value",
           "clear_write_flags", "csv_column_labels", "export_csv", "live_writer", "open_results",
           "read_attributes", "read_checkpoint", "read_results"]

#: rows buffered at most between two writes (the time bound usually flushes first)
CAPACITY = 4096


def attribute_value(value):
    """``value`` as an HDF5 attribute: numbers and numeric lists as numbers and numeric
    arrays, strings and lists of strings as strings; only other objects as JSON text."""
    import h5py

    if isinstance(value, (str, bool, int, float, np.number, np.bool_)):
        return value
    if isinstance(value, np.ndarray) and value.dtype.kind in "biuf":
        return value
    if isinstance(value, (list, tuple)):
        if value and all(isinstance(v, str) for v in value):
            return np.array(value, dtype=h5py.string_dtype())
        try:
            arr = np.asarray(value)
        except ValueError:  # ragged
            arr = None
        if arr is not None and arr.dtype.kind in "biuf":
            return arr
    if value is None:
        return ""
    return json.dumps(value)


def _open_append(path, strict: bool = False):
    """Open a closed results file for writing; a reader holding it open (SWMR readers take a
    shared lock) must not stop the writer from recording how the run ended. ``strict``: no
    such exception (to continue writing steps, nobody else may hold the file)."""
    import h5py

    try:
        return h5py.File(path, "a", libver="latest")
    except BlockingIOError:
        if strict:
            raise BlockingIOError(f"{path} is open in another process (a run writing it, or "
                                  "a reader): close it first") from None
        return h5py.File(path, "a", libver="latest", locking=False)


_SIGNATURE = b"\x89HDF\r\n\x1a\n"


def _lookup3(data: bytes, initval: int = 0) -> int:
    """Bob Jenkins' lookup3 ``hashlittle``: HDF5's metadata checksum (H5_checksum_lookup3)."""
    m = 0xFFFFFFFF

    def rot(x, k):
        return ((x << k) | (x >> (32 - k))) & m

    n = len(data)
    a = b = c = (0xDEADBEEF + n + initval) & m
    i = 0
    while n > 12:
        a = (a + int.from_bytes(data[i:i + 4], "little")) & m
        b = (b + int.from_bytes(data[i + 4:i + 8], "little")) & m
        c = (c + int.from_bytes(data[i + 8:i + 12], "little")) & m
        a = (a - c) & m; a ^= rot(c, 4); c = (c + b) & m  # noqa: E702 - the mix, as published
        b = (b - a) & m; b ^= rot(a, 6); a = (a + c) & m  # noqa: E702
        c = (c - b) & m; c ^= rot(b, 8); b = (b + a) & m  # noqa: E702
        a = (a - c) & m; a ^= rot(c, 16); c = (c + b) & m  # noqa: E702
        b = (b - a) & m; b ^= rot(a, 19); a = (a + c) & m  # noqa: E702
        c = (c - b) & m; c ^= rot(b, 4); b = (b + a) & m  # noqa: E702
        n -= 12
        i += 12
    if n == 0:
        return c
    tail = data[i:] + bytes(12 - n)
    a = (a + int.from_bytes(tail[0:4], "little")) & m
    b = (b + int.from_bytes(tail[4:8], "little")) & m
    c = (c + int.from_bytes(tail[8:12], "little")) & m
    c ^= b; c = (c - rot(b, 14)) & m  # noqa: E702 - the final mix, as published
    a ^= c; a = (a - rot(c, 11)) & m  # noqa: E702
    b ^= a; b = (b - rot(a, 25)) & m  # noqa: E702
    c ^= b; c = (c - rot(b, 16)) & m  # noqa: E702
    a ^= c; a = (a - rot(c, 4)) & m  # noqa: E702
    b ^= a; b = (b - rot(a, 14)) & m  # noqa: E702
    c ^= b; c = (c - rot(b, 24)) & m  # noqa: E702
    return c


def _superblock(path) -> tuple[bytearray, int]:
    """The version-2/3 superblock of an HDF5 file (no user block) and its length."""
    with open(path, "rb") as f:
        head = bytearray(f.read(64))
    if head[:8] != _SIGNATURE or head[8] not in (2, 3):
        raise OSError(f"{path}: not an HDF5 file with a version 2/3 superblock")
    size = 12 + 4 * head[9] + 4  # fields, 4 addresses, checksum
    if _lookup3(bytes(head[:size - 4])) != int.from_bytes(head[size - 4:size], "little"):
        raise OSError(f"{path}: the HDF5 superblock checksum does not match")
    return head, size


def live_writer(path) -> int | None:
    """The id of a process on this machine that holds ``path`` open for writing, or None
    (the file was closed, or its writer is gone: killed, crashed)."""
    try:
        if not _superblock(path)[0][11]:  # HDF5's consistency flags: not open for writing
            return None
        with open_results(path) as f:
            # files of earlier versions keep them at the root
            group = f["resume"] if "resume" in f else f
            where = group.attrs if "writer_pid" in group.attrs else f.attrs
            pid = int(where.get("writer_pid", -1))
            host = str(where.get("writer_host", ""))
    except OSError:
        return None
    if pid <= 0 or host != socket.gethostname():
        return None
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return None
    except PermissionError:  # alive, another user's
        return pid
    return pid


def clear_write_flags(path) -> bool:
    """Clear the write flags a killed writer left in the superblock (what HDF5's ``h5clear
    -s`` does), so that the file opens for writing again; True if there were any."""
    head, size = _superblock(path)
    if not head[11]:
        return False
    head[11] = 0
    head[size - 4:size] = _lookup3(bytes(head[:size - 4])).to_bytes(4, "little")
    with open(path, "r+b") as f:
        f.write(bytes(head[:size]))
    return True


class ResultsWriter:
    """Append rows of named channels to an HDF5 file (module docstring).

    Parameters
    ----------
    path : path
        The .h5 file; created (it must not exist: the caller decides about overwriting).
    channels : dict
        ``name -> (shape, unit, description)``; ``time`` [s] is always present.
    attrs : dict
        Root attributes (:func:`attribute_value`).
    flush_seconds : float
        Longest wall time [s] between two flushes.
    capacity : int
        Rows buffered at most between two writes.
    checkpoint : callable, optional
        ``checkpoint() -> bytes``: the state after the last appended row, stored at each flush.
    dims, coords : optional
        ``dims(name)``: the dimension names of a channel, ``time`` first, and ``coords``: the
        labels of the other dimensions (:mod:`orchestrator.run.channels`). Given, every
        dimension is an HDF5 dimension scale named so (netCDF-4's convention), so that
        xarray (engine ``h5netcdf``) opens the file with labelled dimensions.
    """

    def __init__(self, path, channels: dict, attrs: dict | None = None,
                 flush_seconds: float = 1.0, capacity: int = CAPACITY, checkpoint=None,
                 dims=None, coords: dict | None = None, _resume_rows: int | None = None):
        import h5py

        self.path = Path(path)
        self.channels = {"time": ((), UNITS["time"], DESCRIPTIONS["time"])} | dict(channels)
        self.flush_seconds = float(flush_seconds)
        self.capacity = max(int(capacity), 1)
        self.checkpoint = checkpoint
        self._buf = {name: np.empty((self.capacity, *shape))
                     for name, (shape, _, _) in self.channels.items()}
        self._n = 0  # rows buffered
        if _resume_rows is None:
            self.file = h5py.File(self.path, "x", libver="latest")
            for name, (shape, unit, desc) in self.channels.items():
                ds = self.file.create_dataset(name, shape=(0, *shape), maxshape=(None, *shape),
                                              dtype="f8", chunks=(1024, *shape))
                ds.attrs["units"] = unit
                ds.attrs["description"] = desc
            if dims is not None:
                _label_dimensions(self.file, self.channels, dims, coords or {})
            grp = self.file.create_group("resume")
            for slot in ("slot0", "slot1"):
                grp.create_dataset(slot, shape=(0,), maxshape=(None,), dtype="u1",
                                   chunks=(65536,))
            # [valid slot, bytes, rows] of the last checkpoint; slot -1: none yet
            grp.create_dataset("index", data=np.array([-1, 0, 0], dtype=np.int64))
            grp.attrs["format_version"] = FORMAT_VERSION  # before SWMR: no new attributes
            grp.attrs["format"] = "npz of numeric arrays (fmu_src.state_codec)"
            self.rows = 0
        else:  # continue an existing file after its first _resume_rows rows
            self.file = _open_append(self.path, strict=True)
            self.rows = int(_resume_rows)
            for name in self.channels:
                self.file[name].resize(self.rows, axis=0)
        for key, value in (attrs or {}).items():
            self.file.attrs[key] = attribute_value(value)
        self.file.attrs["complete"] = False
        # live_writer: is a run still writing it? (in a group: not a setting of the run, and
        # xarray's dataset of the file is then the run's Result.to_xarray())
        self.file["resume"].attrs["writer_pid"] = os.getpid()
        self.file["resume"].attrs["writer_host"] = socket.gethostname()
        self.file.swmr_mode = True  # readers may open the file from now on
        self._last = time.monotonic()

    @classmethod
    def resume(cls, path, channels: dict, rows: int, attrs: dict | None = None, **kw):
        """Continue writing ``path`` after its first ``rows`` rows (later rows are dropped:
        they belong to no checkpoint)."""
        return cls(path, channels, attrs, _resume_rows=rows, **kw)

    def append(self, **row) -> None:
        i = self._n
        try:
            for name, buf in self._buf.items():
                buf[i] = row[name]
        except KeyError:
            missing = set(self.channels) - set(row)
            raise ValueError(f"row lacks channels {sorted(missing)}") from None
        self._n = i + 1
        if self._n >= self.capacity or time.monotonic() - self._last >= self.flush_seconds:
            self.flush()

    def append_rows(self, count: int, flush: bool = True, **rows) -> None:
        """``count`` rows at once, each channel ``(count, *shape)``. The checkpoint of a
        flush is the state after the last of them, so rows are written without one until all
        are in; ``flush=False``: none after them either (a block of steps that ended on a
        failed step: the state after it is not one to resume from)."""
        try:
            blocks = [(buf, rows[name]) for name, buf in self._buf.items()]
        except KeyError:
            missing = set(self.channels) - set(rows)
            raise ValueError(f"rows lack channels {sorted(missing)}") from None
        done = 0
        while done < count:
            if self._n >= self.capacity:
                self._write()
            i = self._n
            m = min(count - done, self.capacity - i)
            for buf, values in blocks:
                buf[i:i + m] = values[done:done + m]
            self._n = i + m
            done += m
        if flush and (self._n >= self.capacity
                      or time.monotonic() - self._last >= self.flush_seconds):
            self.flush()

    def _write(self) -> None:
        """Write the buffered rows (no checkpoint, no flush of the file)."""
        n = self._n
        if n:
            for name, buf in self._buf.items():
                ds = self.file[name]
                ds.resize(self.rows + n, axis=0)
                ds[self.rows:self.rows + n] = buf[:n]
            self.rows += n
            self._n = 0

    def flush(self) -> None:
        """Write the buffered rows and the checkpoint, and flush the file."""
        self._write()
        self.file.flush()
        if self.checkpoint is not None:
            self._store_checkpoint(self.checkpoint())
        self._last = time.monotonic()

    def _store_checkpoint(self, state: bytes) -> None:
        grp = self.file["resume"]
        index = grp["index"]
        slot = 1 - int(index[0]) if index[0] >= 0 else 0
        data = np.frombuffer(state, dtype=np.uint8)
        ds = grp[f"slot{slot}"]
        ds.resize(data.size, axis=0)
        ds[:] = data
        self.file.flush()  # the bytes first, then the index that names them
        index[:] = np.array([slot, data.size, self.rows], dtype=np.int64)
        self.file.flush()

    def close(self, complete: bool = True, checkpoint: bool = True, **attrs) -> None:
        """Flush, close, and record how the run ended (``complete`` and ``attrs``).
        ``checkpoint=False``: keep the last checkpoint (the state after the last row is not
        a consistent one, e.g. after a failed step)."""
        if not self.file.id.valid:
            return
        if not checkpoint:
            self.checkpoint = None
        self.flush()
        self.file.close()
        add_attributes(self.path, complete=bool(complete), **attrs)

    def __enter__(self):
        return self

    def __exit__(self, exc_type, exc, tb):
        reason = "" if exc is None else f"{type(exc).__name__}: {exc}"
        self.close(complete=exc is None, checkpoint=exc is None, stopped_by=reason)
        return False


def _label_dimensions(f, channels: dict, dims, coords: dict) -> None:
    """Dimension scales: ``time`` (the channel) and one dataset of labels per other
    dimension, attached to every channel's axes."""
    import h5py

    f["time"].make_scale("time")
    for name, labels in coords.items():
        labels = np.asarray(labels)
        if labels.dtype.kind == "U":
            labels = labels.astype(h5py.string_dtype())
        f.create_dataset(name, data=labels).make_scale(name)
    for name in channels:
        if name == "time":
            continue
        for axis, dim in enumerate(dims(name)):
            f[name].dims[axis].attach_scale(f[dim])


def add_attributes(path, **attrs) -> None:
    """Add (or replace) root attributes of a closed results file (:func:`attribute_value`);
    :func:`read_results` gives them back as numbers, numpy arrays and strings."""
    with _open_append(path) as f:
        for key, value in attrs.items():
            f.attrs[key] = attribute_value(value)


def open_results(path):
    """A results file (a run's or a sweep's) opened for reading, also while a run writes it
    (SWMR); files HDF5 cannot open that way (written without SWMR) open normally."""
    import h5py

    try:
        return h5py.File(path, "r", swmr=True)
    except OSError:
        return h5py.File(path, "r")


def _attributes(f) -> dict:
    return {k: (v.decode() if isinstance(v, bytes) else v) for k, v in f.attrs.items()}


def read_attributes(path) -> dict:
    """The root attributes of a results file (strings decoded), without its channels."""
    with open_results(path) as f:
        return _attributes(f)


def read_results(path) -> dict:
    """All channels as numpy arrays, plus ``attrs`` (root), ``units`` and ``coords`` (the
    labels of the dimensions but time, as strings: ``{"bearing": ("1", ...), ...}``, from the
    file's dimension scales; empty for a file without them); works while the file is being
    written (the rows flushed so far)."""
    with open_results(path) as f:
        names = [n for n in f if _is_channel(f[n])]
        out = {name: f[name][()] for name in names}
        rows = min(len(out[n]) for n in names) if names else 0
        out = {name: v[:rows] for name, v in out.items()}  # channels flushed one by one
        out["units"] = {name: _unit(f[name]) for name in names}
        out["attrs"] = _attributes(f)
        out["coords"] = _labels(f, names)
    return out


def _labels(f, names) -> dict:
    """The labels of the dimension scales attached to the channels ``names`` (time aside)."""
    out = {}
    for name in names:
        proxies = f[name].dims
        for axis in range(1, len(proxies)):
            for scale in proxies[axis].values():
                dim = scale.name.lstrip("/")
                if dim not in out:
                    out[dim] = tuple(v.decode() if isinstance(v, bytes) else str(v)
                                     for v in scale[()])
    return out


def _unit(ds) -> str:
    """A channel's unit (``unit``: files of earlier versions of this package)."""
    return ds.attrs["units"] if "units" in ds.attrs else ds.attrs["unit"]


def _is_channel(item) -> bool:
    """A dataset with a unit (the labels of a dimension have none)."""
    return hasattr(item, "shape") and ("units" in item.attrs or "unit" in item.attrs)


def read_checkpoint(path) -> tuple[int, bytes] | None:
    """``(rows, state)`` of the last checkpoint of a results file, None if it has none;
    :class:`~fmu_src.state_codec.StateFormatError` if its ``format_version`` is not this
    version's (module docstring; the state's bytes are checked when decoded)."""
    with open_results(path) as f:
        if "resume" not in f:
            return None
        slot, nbytes, rows = (int(v) for v in f["resume/index"][()])
        if slot < 0:
            return None
        version = f["resume"].attrs.get("format_version")
        if version is None:
            raise StateFormatError("the checkpoint has no format_version (a file of an older "
                                   "version, whose checkpoints were Python pickles: refused, "
                                   "loading a pickle can run any code)")
        if not isinstance(version, (int, np.integer)) or int(version) != FORMAT_VERSION:
            raise StateFormatError(f"the checkpoint has format version {version!r}; this "
                                   f"version reads version {FORMAT_VERSION}")
        return rows, f[f"resume/slot{slot}"][:nbytes].tobytes()


def csv_column_labels(name: str, shape: tuple, coords: dict | None = None) -> list[str]:
    """The CSV labels of a channel's components in C order: ``name[dimension=label]...``
    with the dimensions of :mod:`orchestrator.run.channels` and the labels ``coords`` (the
    case's names of its bearings, meshes and gears, as in the prints and figures; axes s and
    t), e.g. ``journal_position[bearing=in_a][axis=t]``; a channel not described there, or
    whose labels are not given, numbers its components from 1 (``name[1][2]``). Labels are
    made of letters, digits and ``_`` (:func:`gear_fmu.layout.check_name`): no comma inside
    a label, so any CSV reader splits the header right."""
    coords = coords or {}
    try:
        names = dims(name)[1:]
    except KeyError:
        names = ()
    if len(names) != len(shape) or any(len(coords.get(d, ())) != n
                                       for d, n in zip(names, shape, strict=True)):
        return [name + "".join(f"[{i + 1}]" for i in idx) for idx in np.ndindex(*shape)]
    return [name + "".join(f"[{d}={coords[d][i]}]" for d, i in zip(names, idx, strict=True))
            for idx in np.ndindex(*shape)]


class OlderFileWarning(UserWarning):
    """A results file written by an older version lacks something this version adds."""


#: a run's channels at t = 0, from the static solution its file stores (X0: at rest)
_STATIC_ROW = {"journal_position": "static_journal", "bearing_force": "static_bearing_force",
               "mesh_force": "static_mesh_force",
               "transmission_error": "static_transmission_error",
               "gear_node": "static_gear_node", "iterations": "static_iterations"}


def _static_row(data: dict) -> dict | None:
    """The row at t = 0 of a run's file (the static solution X0, velocities zero), or None
    for a file that is not a run's; a run's file that lacks part of it (written before the
    gear nodes' static positions were stored) is said once."""
    attrs = data["attrs"]
    have = [k for k in _STATIC_ROW.values() if k in attrs]
    if not have or "journal_position" not in data:
        return None
    if len(have) < len(_STATIC_ROW):
        missing = ", ".join(k for k in _STATIC_ROW.values() if k not in attrs)
        warnings.warn(f"no row at t = 0 (X0) in the CSV: the results file stores no {missing} "
                      "(written by an older version); the rows start at the first step",
                      OlderFileWarning, stacklevel=3)
        return None
    row = {name: np.asarray(attrs[key], dtype=float) for name, key in _STATIC_ROW.items()}
    if "static_shaft_speed" in attrs:  # (a file of an earlier version has no shaft speeds)
        row["shaft_speed"] = np.asarray(attrs["static_shaft_speed"], dtype=float)
    row["journal_velocity"] = np.zeros_like(row["journal_position"])
    row["time"] = np.asarray(0.0)
    return row


def export_csv(path, csv_path, channels=None, overwrite: bool = False) -> Path:
    """Write the chosen channels (default: all) as CSV: one row per time step, a column per
    component labelled by :func:`csv_column_labels` with the file's own labels and its unit
    (e.g. ``journal_position[bearing=1][axis=t] [m]``), 17 significant digits. A run's file
    starts at t = 0 with the static solution X0 (journal velocities zero, the iterations
    those of the static solution). Raises FileExistsError if ``csv_path`` exists unless
    ``overwrite``."""
    csv_path = Path(csv_path)
    if csv_path.exists() and not overwrite:
        raise FileExistsError(f"{csv_path} exists")
    data = read_results(path)
    coords = data.pop("coords")
    chosen = channels or [n for n in data if n not in ("units", "attrs")]
    unknown = [n for n in chosen if n not in data or n in ("units", "attrs")]
    if unknown:
        known = [n for n in data if n not in ("units", "attrs")]
        raise ValueError(f"unknown channel(s) {', '.join(unknown)}; the file has "
                         f"{', '.join(known)}")
    names = ["time"] + [n for n in chosen if n != "time"]
    first = _static_row(data)
    if first is not None and any(n not in first for n in names):
        first = None  # a channel without a value at t = 0
    n_rows = len(data["time"]) + (first is not None)
    cols, heads = [], []
    for name in names:
        arr = np.asarray(data[name])
        shape = arr.shape[1:]
        if first is not None:
            arr = np.concatenate([first[name].reshape(1, *shape).astype(arr.dtype), arr])
        flat = arr.reshape(n_rows, -1)
        for j, label in enumerate(csv_column_labels(name, shape, coords)):
            heads.append(f"{label} [{data['units'][name]}]")
            cols.append(flat[:, j])
    np.savetxt(csv_path, np.column_stack(cols), delimiter=",", header=",".join(heads),
               comments="", fmt="%.17g")
    return csv_path
