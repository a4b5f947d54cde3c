"""HDF5 recordings (``.h5``, ``.hdf5``; the optional extra ``algid[hdf5]``, h5py): one 1-D
dataset per signal, named like the CSV columns, at the root or in a given group. A
dataset's unit is in its name (``u1 [N]``) or its ``units`` (or ``unit``) attribute.
Shapes and types are checked before any dataset is read."""

from __future__ import annotations

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


def read_hdf5(path: Path, columns=None, units=None, dt=None, group: str | None = None):
    """Read and validate an HDF5 recording (datasets of ``group``, default the root)."""
    h5py = require("h5py", "hdf5", "HDF5 recordings")
    try:
        fh = h5py.File(path, "r")
    except OSError:
        raise RecordingError(f"{path.name}: not a readable HDF5 file") from None
    with fh:
        if group not in (None, "", "/") and not isinstance(fh.get(group), h5py.Group):
            raise RecordingError(f"{path.name}: no group {quote(group)} (groups: {', '.join(fh)})")
        node = fh[group] if group not in (None, "") else fh
        names = list(node)
        declared = [_unit(node[name].attrs) if isinstance(node[name], h5py.Dataset) else None for name in names]
        layout = resolve(names, path.name, columns, need_time=dt is None, declared=declared)
        used = [names[p] for p in layout.positions()]
        for name in used:
            if not isinstance(node[name], h5py.Dataset):
                raise RecordingError(f"{path.name}: {quote(name)} is a group, not a dataset")
        T = check_columns(path.name, {name: (node[name].shape, node[name].dtype) for name in used})
        data = np.empty((T, len(used)))
        for col, name in enumerate(used):
            data[:, col] = node[name][()]
    return assemble(path, path.name, data, layout, None, dt=dt, units=units)
