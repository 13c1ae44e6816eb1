"""A strict applier of unified diffs, standard library only.

The native layer is built from pythonfmu's pristine sources and this project's patch series
(``fmu_src/native/patches``) on the user's machine, which may have neither ``git`` nor GNU
``patch``. A patch that no longer fits its upstream must stop the build rather than apply
approximately, so there is no fuzz and no offset search: each hunk applies at the line its
header names, its context and removed lines matching byte for byte. Anything else raises
:class:`PatchError` naming the patch, the file and the hunk, and leaves the tree untouched.

Supported: ``diff -u`` and ``git diff`` output (paths with ``a/`` and ``b/``, i.e. ``-p1``)
changing existing text files; free text before the first file is the patch's description.
Creating, deleting, renaming files and binary diffs are refused.
"""

from __future__ import annotations

import re
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path, PurePosixPath

__all__ = ["FilePatch", "Hunk", "Patch", "PatchError", "apply_patch", "apply_series",
           "read_patch"]

_HUNK = re.compile(r"^@@ -(\d+)(?:,(\d+))? \+(\d+)(?:,(\d+))? @@")
#: git's extended header lines for what this applier does not do
_UNSUPPORTED = ("new file mode", "deleted file mode", "rename ", "copy ", "old mode",
                "new mode", "similarity index", "dissimilarity index", "Binary files",
                "GIT binary patch")
_NO_NEWLINE = "\\ No newline at end of file"


class PatchError(ValueError):
    """A patch that cannot be read, or does not apply exactly."""


@dataclass(frozen=True)
class Hunk:
    """One ``@@`` block: ``old`` lines replaced by ``new`` lines from line ``start``."""

    number: int  # 1-based, within its file
    header: str
    start: int
    old: tuple[str, ...]
    new: tuple[str, ...]
    added: tuple[str, ...]


@dataclass(frozen=True)
class FilePatch:
    path: str  # relative to the tree the patch applies to
    hunks: tuple[Hunk, ...]


@dataclass(frozen=True)
class Patch:
    name: str
    description: str
    files: tuple[FilePatch, ...]

    def added_lines(self) -> list[tuple[str, str]]:
        """(path, line) of every line the patch adds."""
        return [(f.path, line) for f in self.files for h in f.hunks for line in h.added]


def _lines(text: str) -> list[str]:
    """The lines of ``text`` with their ``\\n`` (only ``\\n`` splits: ``\\r`` stays)."""
    parts = text.split("\n")
    return [p + "\n" for p in parts[:-1]] + ([parts[-1]] if parts[-1] else [])


def _path(header: str, prefix: str, name: str) -> str:
    raw = header[4:].rstrip("\n").split("\t")[0].strip()
    if raw == "/dev/null":
        raise PatchError(f"{name}: creating or deleting files is not supported ({header!r})")
    if not raw.startswith(prefix):
        raise PatchError(f"{name}: path {raw!r} does not start with {prefix!r} (-p1)")
    rel = PurePosixPath(raw[len(prefix):])
    if rel.is_absolute() or ".." in rel.parts or not rel.parts:
        raise PatchError(f"{name}: path {raw!r} leaves the tree")
    return str(rel)


def _hunk(lines: list[str], i: int, number: int, name: str, path: str) -> tuple[Hunk, int]:
    """The hunk whose header is ``lines[i]``, and the index of the line after it."""
    header = lines[i].rstrip("\n")
    m = _HUNK.match(header)
    where = f"{name}: {path}: hunk {number} ({header})"
    if m is None:
        raise PatchError(f"{where}: not a hunk header")
    old_len = 1 if m.group(2) is None else int(m.group(2))
    new_len = 1 if m.group(4) is None else int(m.group(4))
    start = int(m.group(1)) if old_len else int(m.group(1)) + 1
    old: list[str] = []
    new: list[str] = []
    added: list[str] = []
    last: list[list[str]] = []
    i += 1
    while len(old) < old_len or len(new) < new_len or \
            (i < len(lines) and lines[i].startswith(_NO_NEWLINE)):
        if i >= len(lines):
            raise PatchError(f"{where}: ends before its {old_len} old and {new_len} new lines")
        line = lines[i]
        kind, body = line[:1], line[1:]
        if line == "\n":  # a blank context line whose leading space an editor removed
            kind, body = " ", "\n"
        if kind == "\\" and line.startswith(_NO_NEWLINE) and last:
            for target in last:
                target[-1] = target[-1].removesuffix("\n")
        elif kind in " -+":
            last = [old, new] if kind == " " else [old] if kind == "-" else [new, added]
            for target in last:
                target.append(body)
        else:
            raise PatchError(f"{where}: unexpected line {line!r}")
        if len(old) > old_len or len(new) > new_len:
            raise PatchError(f"{where}: more lines than its header counts")
        i += 1
    return Hunk(number, header, start, tuple(old), tuple(new), tuple(added)), i


def read_patch(path: Path) -> Patch:
    """The patch file ``path``, parsed (its name is the file's name)."""
    name = path.name
    lines = _lines(path.read_bytes().decode("utf-8"))
    description: list[str] = []
    files: list[FilePatch] = []
    in_header = False  # after a "diff ..." line, before its "---"
    i = 0
    while i < len(lines):
        line = lines[i]
        if line.startswith("--- ") and i + 1 < len(lines) and lines[i + 1].startswith("+++ "):
            old_path, new_path = _path(line, "a/", name), _path(lines[i + 1], "b/", name)
            if old_path != new_path:
                raise PatchError(f"{name}: renames are not supported ({old_path} -> {new_path})")
            hunks: list[Hunk] = []
            i += 2
            while i < len(lines) and lines[i].startswith("@@"):
                hunk, i = _hunk(lines, i, len(hunks) + 1, name, old_path)
                hunks.append(hunk)
            if not hunks:
                raise PatchError(f"{name}: {old_path}: no hunks")
            files.append(FilePatch(old_path, tuple(hunks)))
            in_header = False
            continue
        if line.startswith("diff "):
            in_header = True
        elif in_header and line.startswith(_UNSUPPORTED):
            raise PatchError(f"{name}: not supported: {line.rstrip()!r}")
        elif in_header and line.startswith("index "):
            pass
        elif files or in_header:
            raise PatchError(f"{name}: unexpected line {i + 1}: {line!r}")
        else:
            description.append(line)
        i += 1
    if in_header:
        raise PatchError(f"{name}: a file header without its ---/+++ lines")
    if not files:
        raise PatchError(f"{name}: no file to patch")
    return Patch(name, "".join(description).strip(), tuple(files))


def _patched(text: list[str], fp: FilePatch, name: str) -> list[str]:
    out: list[str] = []
    pos = 0  # lines of ``text`` already consumed
    for h in fp.hunks:
        where = f"{name}: {fp.path}: hunk {h.number} ({h.header})"
        at = h.start - 1
        if at < pos:
            raise PatchError(f"{where}: overlaps the hunk before it")
        found = text[at:at + len(h.old)]
        if found != list(h.old):
            bad = next((k for k, (a, b) in enumerate(zip(h.old, found, strict=False))
                        if a != b), len(found))
            expected = h.old[bad] if bad < len(h.old) else "(nothing)"
            got = found[bad] if bad < len(found) else "(end of file)"
            raise PatchError(f"{where}: the context does not match at line {at + bad + 1}: "
                             f"expected {expected!r}, found {got!r}")
        out += text[pos:at] + list(h.new)
        pos = at + len(h.old)
    return out + text[pos:]


def apply_patch(patch: Patch, root: Path) -> None:
    """Apply ``patch`` to the tree ``root``: every hunk exactly, or nothing at all."""
    results: dict[Path, list[str]] = {}
    for fp in patch.files:
        target = root / fp.path
        if target not in results:
            if not target.is_file():
                raise PatchError(f"{patch.name}: {fp.path}: no such file in {root}")
            results[target] = _lines(target.read_bytes().decode("utf-8"))
        results[target] = _patched(results[target], fp, patch.name)
    for target, lines in results.items():
        target.write_bytes("".join(lines).encode("utf-8"))


def apply_series(paths: Iterable[Path], root: Path) -> list[Patch]:
    """Apply the patch files ``paths`` in their order to ``root``; the patches applied."""
    applied = []
    for path in paths:
        patch = read_patch(path)
        apply_patch(patch, root)
        applied.append(patch)
    return applied
