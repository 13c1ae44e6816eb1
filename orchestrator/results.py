"""Results files: HDF5, self-describing, written as the run goes.

One file per run. Each channel is a dataset whose first axis is time, created resizable and
extended in blocks; every block is flushed, so a crash or Ctrl-C keeps everything up to the last
block (the file is closed cleanly on exceptions, including KeyboardInterrupt). Units and
descriptions are attributes of each dataset; the case and the run's settings are attributes of
the root. h5py is used because HDF5 is what NVH and rotordynamics tools open directly.

>>> import tempfile, os, numpy as np
>>> path = os.path.join(tempfile.mkdtemp(), "r.h5")
>>> with ResultsWriter(path, {"x": ((2,), "m", "journal position")}, block=4) as w:
...     for k in range(10):
...         w.append(time=k * 1e-3, x=np.array([k, -k]))
>>> read_results(path)["x"].shape
(10, 2)
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

__all__ = ["ResultsWriter", "add_attributes", "export_csv", "read_results"]


class ResultsWriter:
    """Append rows of named channels to an HDF5 file, flushing every ``block`` rows.

    Parameters
    ----------
    path : path
        The .h5 file (overwritten).
    channels : dict
        ``name -> (shape, unit, description)``; ``time`` [s] is always present.
    attrs : dict
        Root attributes (strings, numbers, or JSON-able objects stored as JSON text).
    block : int
        Rows buffered between writes.
    """

    def __init__(self, path, channels: dict, attrs: dict | None = None, block: int = 1024):
        import h5py

        self.path = Path(path)
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self.file = h5py.File(self.path, "w")
        self.block = int(block)
        self.channels = {"time": ((), "s", "simulated time")} | dict(channels)
        self.rows = 0
        self._n = 0  # rows buffered
        self._buf = {name: np.empty((self.block, *shape))
                     for name, (shape, _, _) in self.channels.items()}
        for name, (shape, unit, desc) in self.channels.items():
            ds = self.file.create_dataset(name, shape=(0, *shape), maxshape=(None, *shape),
                                          dtype="f8", chunks=(max(self.block, 1), *shape))
            ds.attrs["unit"] = unit
            ds.attrs["description"] = desc
        for key, value in (attrs or {}).items():
            self.file.attrs[key] = value if isinstance(value, (str, int, float)) \
                else json.dumps(value)
        self.file.attrs["complete"] = False

    def append(self, **row) -> None:
        missing = set(self.channels) - set(row)
        if missing:
            raise ValueError(f"row lacks channels {sorted(missing)}")
        i = self._n
        for name, buf in self._buf.items():
            buf[i] = row[name]
        self._n = i + 1
        if self._n >= self.block:
            self.flush()

    def flush(self) -> None:
        n = self._n
        if n:
            for name, buf in self._buf.items():
                ds = self.file[name]
                ds.resize(self.rows + n, axis=0)
                ds[self.rows:self.rows + n] = buf[:n]
            self.rows += n
            self._n = 0
        self.file.flush()

    def close(self, complete: bool = True, **attrs) -> None:
        if self.file.id.valid:
            self.flush()
            self.file.attrs["complete"] = bool(complete)
            for key, value in attrs.items():
                self.file.attrs[key] = value if isinstance(value, (str, int, float)) \
                    else json.dumps(value)
            self.file.close()

    def __enter__(self):
        return self

    def __exit__(self, exc_type, exc, tb):
        reason = "" if exc is None else f"{type(exc).__name__}: {exc}"
        self.close(complete=exc is None, stopped_by=reason)
        return False


def add_attributes(path, **attrs) -> None:
    """Add (or replace) root attributes of a closed results file, keeping their types.

    Numbers and numeric numpy arrays are stored as numeric HDF5 attributes, strings as
    strings, lists or tuples of strings as an array of strings; anything else as JSON text
    (as :class:`ResultsWriter` does). :func:`read_results` gives them back as numbers, numpy
    arrays and strings.
    """
    import h5py

    with h5py.File(path, "a") as f:
        for key, value in attrs.items():
            if isinstance(value, (str, int, float, np.number)):
                f.attrs[key] = value
            elif isinstance(value, np.ndarray) and value.dtype.kind in "biuf":
                f.attrs[key] = value
            elif isinstance(value, (list, tuple)) and value \
                    and all(isinstance(v, str) for v in value):
                f.attrs[key] = np.array(value, dtype=h5py.string_dtype())
            else:
                f.attrs[key] = json.dumps(value)


def read_results(path) -> dict:
    """All channels as numpy arrays, plus ``attrs`` (root) and ``units``."""
    import h5py

    with h5py.File(path, "r") as f:
        out = {name: f[name][()] for name in f}
        out["units"] = {name: f[name].attrs["unit"] for name in f}
        out["attrs"] = dict(f.attrs)
    return out


def export_csv(path, csv_path, channels=None) -> Path:
    """Write the chosen channels (default: all) as CSV with ``name [unit]`` headers."""
    data = read_results(path)
    names = ["time"] + [n for n in (channels or data) if n not in ("time", "units", "attrs")]
    cols, heads = [], []
    for name in names:
        arr = data[name].reshape(len(data["time"]), -1)
        for j in range(arr.shape[1]):
            heads.append(f"{name}{'' if arr.shape[1] == 1 else f'[{j}]'} [{data['units'][name]}]")
            cols.append(arr[:, j])
    csv_path = Path(csv_path)
    np.savetxt(csv_path, np.column_stack(cols), delimiter=",", header=",".join(heads),
               comments="")
    return csv_path
