"""Independent pieces of work on a thread per core: the bootstrap's replicates, the diagnosis's
candidates. The estimators release the GIL while they run; :func:`threads` caps the threads
(``algid.fleet`` runs each recording on one, as its workers take a core each)."""

from __future__ import annotations

import os
from concurrent.futures import ThreadPoolExecutor, as_completed
from contextlib import contextmanager
from typing import Callable

#: Threads of :func:`parallel_map`; None: one per core (see :func:`threads`).
_threads: int | None = None


@contextmanager
def threads(count: int | None):
    """Run :func:`parallel_map` on at most ``count`` threads inside the block (None: one per
    core). ``algid.fleet`` runs each recording on one, as its workers take a core each."""
    global _threads
    saved, _threads = _threads, count
    try:
        yield
    finally:
        _threads = saved


def parallel_map(fn: Callable, items: list, progress: Callable[[int], None] | None = None) -> list:
    """``[fn(x) for x in items]`` on a thread per core (the estimators release the GIL while
    they run; at most :func:`threads` ones), results in order; ``progress(done)`` after each."""
    workers = min(len(items), _threads or os.cpu_count() or 1)
    if workers <= 1:
        out = []
        for x in items:
            out.append(fn(x))
            if progress is not None:
                progress(len(out))
        return out
    with ThreadPoolExecutor(max_workers=workers) as pool:
        futures = [pool.submit(fn, x) for x in items]
        for done, _ in enumerate(as_completed(futures), start=1):
            if progress is not None:
                progress(done)
        return [f.result() for f in futures]
