"""``.npz`` recordings: one 1-D array per signal, named like the CSV columns
(``numpy.savez``). Every array's name, shape and type is checked from its header before
any is decompressed."""

from __future__ import annotations

import math
import tokenize
import zipfile
from pathlib import Path

import numpy as np

from ..messages import quote
from .columns import resolve
from .core import RecordingError
from .table import assemble

#: What a damaged archive or ``.npy`` header raises inside zipfile and numpy (a header that
#: ends inside its dict fails in numpy's tokenizer).
_DAMAGED = (zipfile.BadZipFile, ValueError, OSError, EOFError, NotImplementedError, tokenize.TokenError, SyntaxError)


def _members(path: Path) -> dict[str, tuple[tuple[int, ...], np.dtype]]:
    """Name -> (shape, dtype) of every array of an npz, read from the headers only."""
    if not zipfile.is_zipfile(path):
        raise RecordingError(f"{path.name}: not a readable .npz file (not a zip archive)")
    members = {}
    try:
        with zipfile.ZipFile(path) as z:
            for info in z.infolist():
                if not info.filename.endswith(".npy"):
                    raise RecordingError(f"{path.name}: member {quote(info.filename)} is not an .npy array")
                with z.open(info) as fh:
                    version = np.lib.format.read_magic(fh)
                    read_header = {(1, 0): np.lib.format.read_array_header_1_0}.get(
                        version, np.lib.format.read_array_header_2_0
                    )
                    shape, _, dtype = read_header(fh)
                    declared = math.prod(shape) * dtype.itemsize
                    if declared > info.file_size:
                        raise RecordingError(
                            f"{path.name}: array {quote(info.filename)} declares {declared} bytes "
                            f"but holds at most {info.file_size} (truncated or corrupt)"
                        )
                members[info.filename[: -len(".npy")]] = (shape, dtype)
    except RecordingError:
        raise
    except _DAMAGED as err:
        raise RecordingError(f"{path.name}: not a readable .npz file ({type(err).__name__})") from None
    return members


def check_columns(source: str, shapes: dict[str, tuple[tuple[int, ...], np.dtype]]) -> int:
    """The common length of the named 1-D real arrays; raise on any other shape or type."""
    for name, (shape, dtype) in shapes.items():
        if len(shape) != 1:
            raise RecordingError(f"{source}: array {quote(name)} has shape {shape}, expected 1-D")
        if dtype.kind not in "fiu":
            raise RecordingError(f"{source}: array {quote(name)} is not real numeric (dtype {dtype})")
    lengths = {name: shape[0] for name, (shape, _) in shapes.items()}
    first = next(iter(lengths))
    for name, T in lengths.items():
        if T != lengths[first]:
            raise RecordingError(
                f"{source}: ragged arrays: {quote(name)} has {T} samples, {quote(first)} has {lengths[first]}"
            )
    if lengths[first] == 0:
        raise RecordingError(f"{source}: empty file (no samples)")
    return lengths[first]


def read_npz(path: Path, columns=None, units=None, dt=None):
    """Read and validate an ``.npz`` recording."""
    members = _members(path)
    if not members:
        raise RecordingError(f"{path.name}: empty file (no arrays)")
    names = list(members)
    layout = resolve(names, path.name, columns, need_time=dt is None)
    used = [names[p] for p in layout.positions()]
    T = check_columns(path.name, {name: members[name] for name in used})
    data = np.empty((T, len(used)))
    try:
        with np.load(path, allow_pickle=False) as z:
            for col, name in enumerate(used):
                data[:, col] = z[name]
    except _DAMAGED as err:
        raise RecordingError(f"{path.name}: not a readable .npz file ({type(err).__name__})") from None
    return assemble(path, path.name, data, layout, None, dt=dt, units=units)
