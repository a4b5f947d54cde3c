"""HDF5 recordings (``.h5``, ``.hdf5``; the optional extra ``algid[hdf5]``, h5py): one 1-D
dataset per signal, named like the CSV columns, at the root or in a given group. A
dataset's unit is in its name (``u1 [N]``) or its ``units`` (or ``unit``) attribute.
Shapes and types are checked before any dataset is read."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from ..messages import quote
from .columns import resolve
from .core import RecordingError, require
from .npz import check_columns
from .table import assemble


def _unit(attrs) -> str | None:
    for key in ("units", "unit"):
        if key in attrs:
            value = attrs[key]
            return value.decode() if isinstance(value, bytes) else str(value)
    return None


def _check_stored(ds, source: str) -> None:
    """Refuse a contiguous dataset whose header declares more bytes than the file holds for it
    (a damaged size would otherwise be allocated before the read fails)."""
    declared = math.prod(ds.shape) * ds.dtype.itemsize
    stored = ds.id.get_storage_size()
    if ds.chunks is None and declared > stored:
        raise RecordingError(
            f"{source}: dataset {quote(ds.name)} declares {declared} bytes but holds {stored} (truncated or corrupt)"
        )


def _datasets(h5py, fh, source: str, columns, dt, group):
    """The layout of ``group``'s datasets and the (T, columns used) data they hold."""
    if group not in (None, "", "/") and not isinstance(fh.get(group), h5py.Group):
        raise RecordingError(f"{source}: no group {quote(group)} (groups: {', '.join(fh)})")
    node = fh[group] if group not in (None, "") else fh
    names = list(node)
    declared = [_unit(node[name].attrs) if isinstance(node[name], h5py.Dataset) else None for name in names]
    layout = resolve(names, source, columns, need_time=dt is None, declared=declared)
    used = [names[p] for p in layout.positions()]
    for name in used:
        if not isinstance(node[name], h5py.Dataset):
            raise RecordingError(f"{source}: {quote(name)} is a group, not a dataset")
    T = check_columns(source, {name: (node[name].shape, node[name].dtype) for name in used})
    for name in used:
        _check_stored(node[name], source)
    data = np.empty((T, len(used)))
    for col, name in enumerate(used):
        data[:, col] = node[name][()]
    return layout, data


def read_hdf5(path: Path, columns=None, units=None, dt=None, group: str | None = None):
    """Read and validate an HDF5 recording (datasets of ``group``, default the root)."""
    h5py = require("h5py", "hdf5", "HDF5 recordings")
    try:
        with h5py.File(path, "r") as fh:
            layout, data = _datasets(h5py, fh, path.name, columns, dt, group)
    except RecordingError:
        raise
    except (OSError, KeyError, ValueError, TypeError, RuntimeError) as err:
        # a damaged file fails inside the HDF5 library as any of these, at any object
        raise RecordingError(f"{path.name}: not a readable HDF5 file ({type(err).__name__})") from None
    return assemble(path, path.name, data, layout, None, dt=dt, units=units)
