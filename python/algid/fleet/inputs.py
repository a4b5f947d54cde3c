"""The recordings named by ``algid batch INPUTS``: files, folders (searched recursively) and
glob patterns (``**`` included), each recording once, in a stable order."""

from __future__ import annotations

import glob
import json
from pathlib import Path

from ..messages import quote, quote_path
from ..recording import EXTENSIONS, readable
from ..recording.options import READING, mapping_file


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


def read_layouts(path: Path) -> list[list]:
    """``[[pattern, reading], ...]`` from a JSON or TOML file mapping glob patterns to the reading
    options of the files they match (``{"rig_a/*.csv": {"force": "F1", "accel": "acc1", "units":
    "acceleration=g"}}``), in the file's order; a ``columns`` name is a ``--columns`` JSON file
    beside it. Raises :class:`InputError` on an unreadable file or an unknown option."""
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as err:
        raise InputError(f"--layouts: cannot read {quote_path(path)} ({err.strerror or err})") from None
    try:
        if path.suffix.lower() == ".toml":
            import tomllib

            table = tomllib.loads(text)
        else:
            table = json.loads(text)
    except ValueError as err:
        raise InputError(f"--layouts: {quote_path(path)} is not {path.suffix.lower()[1:] or 'JSON'} ({err})") from None
    if not isinstance(table, dict) or not all(isinstance(v, dict) for v in table.values()):
        raise InputError(f"--layouts: {quote_path(path)} must map glob patterns to tables of options")
    layouts = []
    for pattern, reading in table.items():
        unknown = sorted(set(reading) - set(READING))
        if unknown:
            raise InputError(
                f"--layouts: {quote(pattern)}: unknown option {quote(unknown[0])} (known: {', '.join(READING)})"
            )
        if isinstance(reading.get("columns"), str):
            reading = {**reading, "columns": mapping_file(path.parent / reading["columns"])}
        layouts.append([pattern, reading])
    return layouts
