"""The results of a batch: Parquet part files ``DIR/results/part-*.parquet``, one per flush of
completed rows, read back as one table.

A part is written to a hidden temporary name and renamed into place, so a batch killed at any
moment leaves whole parts only (a stray temporary is removed when the store is opened). A row
written twice (a task retried after its first result was already flushed, two batches over the
same recordings) appears once when read: the last written row of each key is kept.
"""

from __future__ import annotations

import os
import time
from itertools import count
from pathlib import Path

#: Folder of the part files inside the output folder.
RESULTS = "results"


class ResultStore:
    """Append-only Parquet parts in ``out/results``; :meth:`read` gives one row per key."""

    def __init__(self, out: str | Path) -> None:
        self.folder = Path(out) / RESULTS
        self.folder.mkdir(parents=True, exist_ok=True)
        for stray in self.folder.glob(".part-*.tmp"):
            stray.unlink()
        self._seq = count()
        self._stamp = f"{time.strftime('%Y%m%dT%H%M%S')}-{os.getpid()}"

    def parts(self) -> list[Path]:
        """The part files, oldest first (their names sort by time of writing)."""
        return sorted(self.folder.glob("part-*.parquet"))

    def write(self, rows: list[dict]) -> Path | None:
        """Append ``rows`` as one part file; returns its path (None for no rows)."""
        import pandas as pd
        import pyarrow as pa
        import pyarrow.parquet as pq

        if not rows:
            return None
        table = pd.DataFrame(rows)
        table["recorded_at"] = pd.to_datetime(table.get("recorded_at"), unit="s", utc=True)
        arrow = pa.Table.from_pandas(table, preserve_index=False)
        # a column with no value in this part (no error among its rows) is text, as in the others
        arrow = arrow.cast(
            pa.schema([f.with_type(pa.string()) if pa.types.is_null(f.type) else f for f in arrow.schema])
        )
        name = f"part-{self._stamp}-{next(self._seq):06d}.parquet"
        tmp = self.folder / f".{name}.tmp"
        pq.write_table(arrow, tmp)
        os.replace(tmp, self.folder / name)
        return self.folder / name

    def read(self):
        """Every row written, one per key (the last written), as a pandas DataFrame."""
        import pandas as pd
        import pyarrow.parquet as pq

        frames = [pq.read_table(p).to_pandas() for p in self.parts()]
        frames = [f for f in frames if len(f)]
        if not frames:
            return pd.DataFrame(columns=["key", "path", "status", "error"])
        table = pd.concat(frames, ignore_index=True)
        # keyless rows (a file that could not even be read) count once per path
        ident = table["key"].where(table["key"].notna(), "path:" + table["path"])
        return table[~ident.duplicated(keep="last")].reset_index(drop=True)

    def done(self) -> frozenset:
        """Keys of the rows written (ok or failed: a recording's failure is its result)."""
        import pyarrow.parquet as pq

        keys = set()
        for part in self.parts():
            keys.update(k for k in pq.read_table(part, columns=["key"]).column("key").to_pylist() if k is not None)
        return frozenset(keys)
