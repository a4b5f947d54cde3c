"""The recordings named by ``algid batch INPUTS``: files, folders (searched recursively) and
glob patterns (``**`` included), each recording once, in a stable order."""

from __future__ import annotations

import glob
from pathlib import Path

from ..messages import quote_path
from ..recording import EXTENSIONS, readable


class InputError(ValueError):
    """An input that names no recording; ``str(err)`` is one line."""


def _in_folder(folder: Path) -> list[Path]:
    return sorted(p for p in folder.rglob("*") if p.is_file() and readable(p))


def expand(inputs) -> list[Path]:
    """Absolute paths of the recordings ``inputs`` name, sorted, without repeats.

    A file is taken whatever its suffix (the reader then says whether it can read it); a
    folder contributes its files with an extension the reader reads (:func:`algid.recording.readable`);
    a pattern with ``*``, ``?`` or ``[`` is expanded like a folder's listing. An input naming
    nothing raises :class:`InputError`.
    """
    if isinstance(inputs, (str, Path)):
        inputs = [inputs]
    found: dict[Path, None] = {}
    for item in inputs:
        path = Path(item)
        if path.is_dir():
            hits = _in_folder(path)
        elif path.exists():
            hits = [path]
        elif any(c in str(item) for c in "*?["):
            matched = sorted(Path(p) for p in glob.glob(str(item), recursive=True))
            hits = [p for p in matched if p.is_file() and readable(p)]
            hits += [q for p in matched if p.is_dir() for q in _in_folder(p)]
        else:
            raise InputError(f"no such file or folder: {quote_path(path)}")
        if not hits:
            raise InputError(f"no recordings ({EXTENSIONS}) in {quote_path(path)}")
        found.update(dict.fromkeys(p.resolve() for p in hits))
    return sorted(found)
