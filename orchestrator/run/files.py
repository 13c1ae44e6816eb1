"""Where a run writes: one results file per set of effective parameters, never clobbered.

A run's file is ``<out>/<case>_<model>[_inprocess]_<hash>.h5``, the hash (8 hex digits of a
SHA-256) taken over the effective case (every field after the overrides, ``--periods``
included), the transport and, for a bearing FMU of the user's own, the FMU file's bytes. Two
runs with different overrides therefore write two files. The same run twice finds its file:
complete, the run answers from it (``Target.stored``; nothing is computed, ``--overwrite``
computes it again); incomplete, it stops with a message (``--resume`` continues it,
``--overwrite`` replaces it). The name alone is never trusted: a file whose stored inputs (the
case, the transport, the bearing model or FMU, the number of steps) differ from the run's is
neither reused nor replaced, ``--overwrite`` or not (:func:`input_difference`).

With ``--overwrite`` over a complete file the new run writes ``<name>.partial.h5`` and
replaces the old file only once it is complete: a run that fails or is interrupted leaves the
complete file untouched, and its own steps in the ``.partial.h5`` file. Figures live in the
folder ``<out>/<name>/`` beside the file they were drawn from.
"""

from __future__ import annotations

import hashlib
import os
from dataclasses import dataclass
from pathlib import Path

__all__ = ["PartialFileWarning", "Target", "TargetError", "describe_file", "input_difference",
           "results_name", "target"]


class PartialFileWarning(UserWarning):
    """A ``<name>.partial.h5`` beside a run's complete file: the steps of an ``--overwrite``
    that did not complete, which the run names (kept, or replaced by a new ``--overwrite``)."""


class TargetError(RuntimeError):
    """The results file cannot be written (message names the file and what to do)."""


def results_name(case, label: str, in_process: bool, steps: int | None = None,
                 bearing_fmu: Path | str | None = None) -> str:
    """``<case>_<label>[_inprocess]_<hash>`` (module docstring)."""
    h = hashlib.sha256(_case_body(case.to_toml(header=False)).encode())
    h.update(f"\nlabel={label}\nin_process={bool(in_process)}\nsteps={steps}\n".encode())
    if bearing_fmu is not None:
        h.update(Path(bearing_fmu).read_bytes())
    suffix = "_inprocess" if in_process else ""
    return f"{case['case.name']}_{label}{suffix}_{h.hexdigest()[:8]}"


def describe_file(path: Path) -> str:
    """What a results file holds, in a few words (complete, interrupted, being written)."""
    from orchestrator.run.results import open_results

    try:
        with open_results(path) as f:
            n = f["time"].shape[0] if "time" in f else 0
            complete = bool(f.attrs.get("complete", False))
            why = str(f.attrs.get("stopped_by", ""))
    except BlockingIOError:
        return "open for writing by another run"
    except OSError as exc:
        return f"not a readable results file ({exc})"
    if complete:
        return f"complete, {n} steps"
    if why and not why.startswith("interrupted"):  # "interrupted by SIGINT after ..."
        why = f"stopped by {why}"
    return f"incomplete, {n} steps" + (f", {why}" if why else "")


#: the root attributes that, with the case, say what a results file was computed from
INPUTS = ("mode", "bearing_model", "bearing_fmu_sha256", "steps_total")


def _case_body(toml: str) -> str:
    """A stored case file without its header comment (which names where it was read from)
    and without ``simulation.window``: the window chooses what the report is taken over, not
    what is computed, so runs that differ in it alone are the same run (and keep the names
    they had before the field existed)."""
    lines = str(toml).split("\n")
    while lines and lines[0].startswith("#"):
        lines.pop(0)
    section = ""
    kept = []
    for line in lines:
        if line.startswith("["):
            section = line
        if not (section == "[simulation]" and line.startswith("window = ")):
            kept.append(line)
    return "\n".join(kept)


def _plain(value) -> str:
    """An attribute's value as a message shows it: numbers as numbers (not numpy reprs),
    text quoted."""
    value = value.item() if hasattr(value, "item") else value
    return f"'{value}'" if isinstance(value, str) else str(value)


def input_difference(path: Path, expected: dict, ignore=()) -> str | None:
    """None if the results file ``path`` was computed from the inputs of ``expected`` (the
    root attributes of the run about to start: :meth:`orchestrator.run.spec.RunSpec.attributes`),
    else what differs, in a few words; the :data:`INPUTS` in ``ignore`` are not compared."""
    from orchestrator.run.results import read_attributes

    try:
        stored = read_attributes(path)
    except OSError as exc:
        return f"its attributes cannot be read ({exc})"
    if "case_toml" not in stored:
        return "it stores no case (a file of another version or program)"
    if _case_body(stored["case_toml"]) != _case_body(expected["case_toml"]):
        return "another case (some field of the stored case differs)"
    for key in INPUTS:
        a, b = stored.get(key, ""), expected.get(key, "")
        if key not in ignore and str(a) != str(b):
            return f"{key} {_plain(a)}, this run's {_plain(b)}"
    return None


@dataclass
class Target:
    """Where a run writes (``write``) and the file it becomes when complete (``final``);
    ``stored``: ``final`` is complete and holds this very run, read instead of computed."""

    write: Path
    final: Path
    stored: bool = False

    def finish(self, complete: bool) -> Path:
        """Move the written file into place: always when complete; when not, only if no
        complete file would be replaced. Returns where the run's steps now are."""
        if self.write == self.final:
            return self.final
        if complete or not _is_complete(self.final):
            os.replace(self.write, self.final)
            return self.final
        return self.write


def _is_complete(path: Path) -> bool:
    from orchestrator.run.results import read_attributes

    try:
        return bool(read_attributes(path).get("complete", False))
    except OSError:
        return False


def target(out_dir: Path | str, name: str, overwrite: bool, expected: dict | None = None
           ) -> Target:
    """Decide where a run named ``name`` writes in ``out_dir`` (module docstring); checks
    that the folder can be created and written before anything is computed. ``expected``:
    the root attributes of the run (:func:`input_difference`); without them an existing
    complete file is never reused."""
    out_dir = Path(out_dir)
    try:
        out_dir.mkdir(parents=True, exist_ok=True)
    except FileExistsError:
        raise TargetError(f"--out {out_dir}: is a file, not a folder") from None
    except OSError as exc:
        raise TargetError(f"--out {out_dir}: cannot create the folder ({exc.strerror})") \
            from None
    if not os.access(out_dir, os.W_OK | os.X_OK):
        raise TargetError(f"--out {out_dir}: the folder is not writable")
    final = out_dir / f"{name}.h5"
    if not final.exists():
        return Target(final, final)
    from orchestrator.run.results import live_writer

    pid = live_writer(final)
    if pid is not None:
        raise TargetError(f"{final} is being written by another run (process {pid}); wait for "
                          "it, stop it, or use another --out")
    state = describe_file(final)
    readable = state.startswith(("complete", "incomplete"))
    differ = input_difference(final, expected) if readable and expected is not None else None
    if differ is not None and input_difference(final, expected, ("steps_total",)) is None:
        # the same inputs over another length: a run resumed with another --periods
        if not overwrite:
            raise TargetError(f"{final} exists ({state}): a run of the same inputs but of "
                              f"another length ({differ}; a run resumed with another "
                              "--periods); --overwrite replaces it, or another --out")
        differ = None
    if differ is not None:
        raise TargetError(f"{final} exists ({state}) but holds a run of other inputs "
                          f"({differ}): it is neither reused nor replaced; move it away or "
                          "use another --out")
    complete = state.startswith("complete")
    partial = out_dir / f"{name}.partial.h5"
    if complete and partial.exists():
        import warnings

        fate = ("this --overwrite replaces it" if overwrite else
                "kept; the next --overwrite replaces it")
        warnings.warn(f"{partial} ({describe_file(partial)}) holds the steps of an --overwrite "
                      f"of {final.name} that did not complete: {fate}", PartialFileWarning,
                      stacklevel=2)
    if complete and not overwrite and expected is not None:
        return Target(final, final, stored=True)
    if not overwrite:
        hint = "" if complete else f", --resume {final} to continue it"
        raise TargetError(f"{final} exists ({state}): this run would overwrite it; "
                          f"--overwrite to replace it{hint}, or another --out")
    if complete:
        partial.unlink(missing_ok=True)
        return Target(partial, final)
    final.unlink()
    return Target(final, final)
