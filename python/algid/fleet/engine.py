"""``algid.batch(paths, out)``: every recording identified (and diagnosed) on Dask, its row
written to Parquet as soon as a part's worth is done.

Dask's idiom for many files: the client sends file *names*; the workers hash, load and
analyse (:func:`.task.run_one`). At most :data:`IN_FLIGHT_PER_THREAD` tasks per worker thread
are submitted at a time (a sliding window over :func:`distributed.as_completed`), so the
client and the scheduler hold a bounded number of futures however many recordings there are.
The keys already in the output are scattered to every worker once; a worker skips a recording
whose key is among them. A task whose worker dies is rescheduled by Dask (``retries`` and the
scheduler's ``allowed-failures``); when every worker holding the scattered keys has died (a
cluster of one worker), the keys are scattered again and the tasks that needed them are
submitted again. If Dask gives up, the recording's row says so and carries no key, so the next
run of the batch tries it again.

The embedded cluster is a ``LocalCluster`` of ``workers`` processes with one thread each (the
work is numpy and C++ that holds the GIL between calls: processes, not threads), each limited
to its share of the machine's memory, its logs silenced below errors, Dask's profiler off
and its in-memory logs short (:data:`WORKER_CONFIG`).
"""

from __future__ import annotations

import json
import logging
import os
import time
from pathlib import Path
from typing import Callable, Optional

from ..identification.surrogate import REPLICATES
from .inputs import expand, read_layouts
from .store import ResultStore
from .task import Options, run_one

#: Tasks in flight per worker thread.
IN_FLIGHT_PER_THREAD = 4
#: Rows per Parquet part, and the longest time [s] completed rows wait before they are written.
PART_ROWS = 64
PART_SECONDS = 30.0
#: Times Dask reruns a task whose worker failed, on top of the scheduler's own allowance.
RETRIES = 2

#: Worker settings of the embedded cluster (merged into this process's Dask configuration).
#: Dask's statistical profiler keeps the call trees of its last 1000 one-second cycles per worker
#: (about 17 min): memory that grows recording by recording for that long; it is off. The system
#: monitor keeps 7200 half-second samples (an hour) and the developers' logs 1000 entries each:
#: 5 min and 100 entries here (what each costs a worker: docs/fleet.md).
WORKER_CONFIG = {
    "worker": {"profile": {"enabled": False}},
    "admin": {"low-level-log-length": 100, "system-monitor": {"log-length": 600}},
}

ProgressFn = Optional[Callable[[dict, int], None]]


def _topology_json(topology) -> str:
    """:attr:`.task.Options.topology` of a network, the path of its JSON, or None (``""``)."""
    if topology is None:
        return ""
    from ..model.network import Network

    net = topology if isinstance(topology, Network) else Network.from_json(topology)
    return json.dumps(net.to_json(), sort_keys=True)


def local_cluster(workers: int | None = None):
    """A ``LocalCluster`` of ``workers`` single-threaded processes (default: the machine's cores)."""
    import dask
    from distributed import LocalCluster

    n = int(workers or os.cpu_count() or 1)
    if n < 1:
        raise ValueError(f"workers must be >= 1, got {workers}")
    return LocalCluster(
        n_workers=n,
        threads_per_worker=1,
        processes=True,
        memory_limit="auto",  # the machine's memory shared out among the workers
        dashboard_address=":0",  # any free port: never a clash with another cluster's 8787
        silence_logs=logging.ERROR,
        # The nannies start (and restart) their workers with this configuration.
        config={"distributed": dask.config.merge(dask.config.get("distributed"), WORKER_CONFIG)},
    )


class _Writer:
    """Completed rows buffered and flushed as Parquet parts (every ``rows`` or ``seconds``)."""

    def __init__(self, store: ResultStore, rows: int, seconds: float) -> None:
        self.store, self.rows, self.seconds = store, int(rows), float(seconds)
        self.buffer: list[dict] = []
        self.last = time.monotonic()

    def add(self, row: dict) -> None:
        self.buffer.append(row)
        if len(self.buffer) >= self.rows or time.monotonic() - self.last >= self.seconds:
            self.flush()

    def flush(self) -> None:
        self.store.write(self.buffer)
        self.buffer, self.last = [], time.monotonic()


def _lost_row(path: Path, err: BaseException) -> dict:
    from ..messages import error_text

    row = {"key": None, "path": str(path), "name": path.name, "machine": path.parent.name, "status": "failed"}
    return {**row, "error": f"lost by Dask: {error_text(err)}"}


def _scatter(client, keys: set):
    """The keys already in the output, on every worker (one object, not its elements)."""
    (future,) = client.scatter([keys], broadcast=True, hash=False)
    return future


def _run(client, paths: list[Path], options: Options, writer: _Writer, progress: ProgressFn) -> tuple[dict, list]:
    """Submit the paths through a sliding window; returns the counts and this run's keys."""
    from distributed import as_completed

    known = writer.store.done()
    done = _scatter(client, known)
    window = IN_FLIGHT_PER_THREAD * max(1, sum(client.nthreads().values()))
    pending = iter(paths)
    origin: dict = {}  # future key -> (path, times its scattered input was lost, that input)

    def submit(path: Path, lost: int = 0):
        future = client.submit(run_one, str(path), options, done, pure=False, retries=RETRIES)
        origin[future.key] = (path, lost, done)
        return future

    queue = as_completed([submit(p) for _, p in zip(range(window), pending)])
    counts, keys = {"ok": 0, "failed": 0, "skipped": 0}, []
    try:
        for future in queue:
            path, lost, used = origin.pop(future.key)
            try:
                row = future.result()
            except Exception as err:  # noqa: BLE001 - a task Dask gave up on (its worker kept dying)
                if used.status != "finished" and lost < RETRIES:
                    # the workers holding the scattered keys all died: scatter them again (once)
                    if done is used:
                        done = _scatter(client, known)
                    future.release()
                    queue.add(submit(path, lost + 1))
                    continue
                row = _lost_row(path, err)
            future.release()
            counts[row["status"]] += 1
            keys.append(row["key"] or "path:" + row["path"])
            if row["status"] != "skipped":
                writer.add(row)
            nxt = next(pending, None)
            if nxt is not None:
                queue.add(submit(nxt))
            if progress is not None:
                progress(counts, len(paths))
    finally:  # an interrupted batch (Ctrl-C) keeps the rows it has
        writer.flush()
    return counts, keys


def batch(
    paths,
    out: str | Path,
    client=None,
    *,
    workers: int | None = None,
    diagnose: bool = False,
    boundary: str = "fixed",
    estimator: str = "auto",
    replicates: int | None = None,
    part_rows: int = PART_ROWS,
    part_seconds: float = PART_SECONDS,
    progress: ProgressFn = None,
    reading: dict | None = None,
    layouts: str | Path | list | None = None,
    topology=None,
):
    """Identify (and with ``diagnose`` diagnose) every recording ``paths`` name, on Dask.

    Parameters
    ----------
    paths : file, folder or glob pattern, or a list of them (:func:`.inputs.expand`).
    out : output folder; the rows go to ``out/results/part-*.parquet``. Recordings whose
        key (content, algid version, options) is already there are skipped.
    client : a ``distributed.Client`` to run on; None starts a ``LocalCluster`` of
        ``workers`` processes for the batch and closes it after.
    diagnose, boundary, estimator, replicates : as ``algid diagnose`` / ``algid identify``.
    reading : how to read every file, as ``algid identify``'s options say (``{"force": "F1",
        "accel": "acc1", "units": "acceleration=g", "rate": 2048}``,
        :func:`algid.recording.options.reading_options`).
    topology : a spring network (:class:`algid.Network`, or the path of its JSON) to identify
        (and diagnose) every recording on, as ``algid identify --topology``; None: the chain.
    layouts : for folders of mixed layouts, glob pattern -> reading options over ``reading``: a
        JSON or TOML file (:func:`.inputs.read_layouts`) or its ``[[pattern, reading], ...]``.
    part_rows, part_seconds : a part file is written every ``part_rows`` rows or
        ``part_seconds`` [s], whichever comes first.
    progress : called after every recording with the counts ``{"ok", "failed", "skipped"}`` and
        the number of recordings in the batch.

    Returns
    -------
    pandas.DataFrame
        One row per recording of this batch (skipped ones as written before), the columns
        of :mod:`.task`; ``df.attrs["counts"]`` holds the counts ok / failed / skipped.
    """
    from .deps import require

    require()
    found = expand(paths)
    if isinstance(layouts, (str, Path)):
        layouts = read_layouts(layouts)
    options = Options(
        boundary,
        estimator,
        REPLICATES if replicates is None else int(replicates),
        bool(diagnose),
        json.dumps(reading or {}, sort_keys=True),
        json.dumps(layouts or []),
        _topology_json(topology),
    )
    store = ResultStore(out)
    writer = _Writer(store, part_rows, part_seconds)
    if client is not None:
        counts, keys = _run(client, found, options, writer, progress)
    else:
        from distributed import Client

        with local_cluster(workers) as cluster, Client(cluster) as own:
            counts, keys = _run(own, found, options, writer, progress)
    table = store.read()
    ident = table["key"].where(table["key"].notna(), "path:" + table["path"].astype(str))
    rows = table[ident.isin(set(keys))].reset_index(drop=True)
    rows.attrs["counts"] = counts
    return rows
