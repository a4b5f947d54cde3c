"""Fleets of recordings: every recording of folders, files and glob patterns identified (and
diagnosed) on Dask, one Parquet row per recording, resumable (``algid batch``, issue 22).

:mod:`.inputs` expands the inputs into recording paths, :mod:`.task` is what a worker runs on
one path, :mod:`.store` the incremental Parquet results, :mod:`.engine` drives the batch on a
Dask client, :mod:`.summary` the per-machine table; the plots are in
:mod:`algid.plotting.batch`. Needs the ``batch`` extra (dask[distributed], pyarrow, pandas)
only when a batch runs: importing this package costs nothing.
"""

from .engine import batch
from .task import Options

__all__ = ["Options", "batch"]
