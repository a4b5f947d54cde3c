"""What a worker does with one recording: hash it, skip it if done, else load, identify (and
diagnose) it and return its row; a bad recording becomes a row with its one-line error.

The row holds what ``algid identify --json`` and ``algid diagnose --json`` write for the same
file (the same functions make both), flattened to columns:

* ``key`` sha256 of the file's bytes, the algid version and the :class:`Options`; ``path``,
  ``name``, ``machine`` (the folder's name), ``recorded_at`` (the file's modification time);
* ``status`` ``ok`` or ``failed``, ``error`` the one line of a failure;
* ``n``, ``boundary`` (None on a network), on a network ``springs`` (JSON), ``estimator``,
  ``samples``, ``duration_s``, ``fs_hz``, ``valid``, ``valid_parameters``, ``reasons``; per
  parameter ``m1..``, ``c1..``, ``k1..`` [kg, N s/m, N/m] and ``sigma_m1..``; the undamped
  natural frequencies ``f1_hz..`` of the estimates;
* with ``diagnose``: ``effect``, ``location`` and ``params`` (JSON), ``gap_before``, ``gap_after``;
* ``load_s``, ``identify_s``, ``diagnose_s``, ``task_s`` [s], ``cpu_s`` (the worker process's CPU
  time over the task [s]: below ``task_s`` when the worker waited for a core), ``finished_at``
  [s since the epoch],
  ``worker_pid``, ``rss_mb``
  (the worker's resident memory after the recording [MiB]), ``algid_version``.
"""

from __future__ import annotations

import hashlib
import json
import os
import time
from dataclasses import asdict, dataclass
from pathlib import Path, PurePath

import numpy as np

from ..identification.surrogate import REPLICATES
from ..parallel import threads

#: Bytes hashed at a time (the hash never holds a whole file).
HASH_BLOCK = 1 << 20


@dataclass(frozen=True)
class Options:
    """The settings that change a recording's result (they enter its key).

    boundary : right end of the chain, ``fixed`` or ``free``.
    topology : JSON of a spring network (:meth:`algid.Network.to_json`) every recording is
        identified (and diagnosed) on instead of the chain, ``""`` for the chain; with it the
        boundary stays ``fixed`` and the estimator ``auto`` (a network's fit has neither).
    estimator : ``auto``, ``window`` or ``continuous`` (:func:`algid.identify`).
    replicates : bootstrap replicates of the uncertainties.
    diagnose : also run :func:`algid.diagnosis.diagnose`.
    reading : JSON of the reading options of every file (the keywords of
        :func:`algid.recording.options.reading_options`: ``{"force": "F1", "units": "acceleration=g"}``).
    layouts : JSON of ``[[pattern, reading], ...]``: a file that a glob pattern matches (from the
        right, :meth:`pathlib.PurePath.match`) is read with the first such pattern's options over
        ``reading`` (:func:`.inputs.read_layouts`).
    """

    boundary: str = "fixed"
    estimator: str = "auto"
    replicates: int = REPLICATES
    diagnose: bool = False
    reading: str = "{}"
    layouts: str = "[]"
    topology: str = ""

    def __post_init__(self) -> None:
        from ..identification.plan import ESTIMATORS

        if self.boundary not in ("fixed", "free"):
            raise ValueError(f"boundary must be 'fixed' or 'free', got {self.boundary!r}")
        if self.estimator not in ESTIMATORS:
            raise ValueError(f"estimator must be one of {', '.join(ESTIMATORS)}, got {self.estimator!r}")
        if self.replicates < 2:
            raise ValueError(f"replicates must be >= 2, got {self.replicates}")
        self.reading_for("")  # the options are known keywords with readable values
        if self.topology:
            from ..identification.network import refuse_chain_options

            self.network()
            refuse_chain_options(self.boundary, self.estimator)

    def network(self):
        """The :class:`algid.Network` of ``topology``, or the chain's boundary (``fixed``, ``free``)
        without one: what :func:`algid.identify` and :func:`algid.diagnosis.diagnose` take."""
        from ..model.network import Network

        return Network.from_json(json.loads(self.topology)) if self.topology else self.boundary

    def reading_for(self, path) -> dict:
        """The keyword arguments of :func:`algid.recording.load_recording` for the file at ``path``."""
        from ..recording.options import reading_options

        given = json.loads(self.reading)
        for pattern, layout in json.loads(self.layouts):
            if path and PurePath(path).match(pattern):
                given = {**given, **layout}
                break
        try:
            return reading_options(**given)
        except TypeError as err:
            raise ValueError(f"reading options: {err}") from None

    def fingerprint(self) -> bytes:
        """The options and the algid version, canonically serialised (``topology`` only when
        given: a chain's key is the one it had before networks)."""
        from .. import __version__

        options = {k: v for k, v in asdict(self).items() if k != "topology" or v}
        return json.dumps({**options, "algid": __version__}, sort_keys=True).encode()


def content_key(path: Path, options: Options) -> str:
    """sha256 of the file's bytes, then of ``options.fingerprint()``: the row's key."""
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(HASH_BLOCK), b""):
            h.update(block)
    h.update(b"\0")
    h.update(options.fingerprint())
    return h.hexdigest()


def _rss_mb() -> float:
    import psutil  # a dependency of distributed

    return psutil.Process().memory_info().rss / 2**20


def _identification_columns(doc: dict) -> dict:
    """Columns of an ``algid identify`` JSON document."""
    row = {"n": doc["n"], "boundary": doc.get("boundary")}
    if "springs" in doc:
        row["springs"] = json.dumps(doc["springs"])
    row.update({key: doc[key] for key in ("estimator", "samples", "duration_s", "valid")})
    row["fs_hz"] = 1.0 / doc["dt_s"]
    row["valid_parameters"] = sum(p["valid"] for p in doc["parameters"])
    row["reasons"] = "; ".join(doc["reasons"])
    for p in doc["parameters"]:
        row[p["name"]] = _float(p["value"])
        row[f"sigma_{p['name']}"] = _float(p["sigma"])
    return row


def _diagnosis_columns(doc: dict) -> dict:
    """Columns of an ``algid diagnose`` JSON document."""
    return {
        "effect": doc["effect"],
        "location": json.dumps(doc["location"]),
        "params": json.dumps(doc["params"]),
        "gap_before": _float(doc["gap_before"]),
        "gap_after": _float(doc["gap_after"]),
    }


def _float(v) -> float:
    return float("nan") if v is None else float(v)


def _frequencies_hz(result) -> np.ndarray:
    """Undamped natural frequencies [Hz] of the estimates; empty when they are not a physical
    chain or network (a parameter without an estimate, a mass not positive, a spring negative)."""
    from ..identification.plan import natural_frequencies_hz
    from ..model.network import NetworkModel

    if not result.network:
        return natural_frequencies_hz(result.theta, result.n, result.boundary)
    try:
        return NetworkModel.from_packed(result.theta, result.network).natural_frequencies_hz()
    except ValueError:
        return np.array([])


def _analyse(path: Path, options: Options) -> dict:
    """The result columns of one recording (raises on a bad one)."""
    from ..diagnosis import diagnose
    from ..diagnosis.report import to_json as diagnosis_json
    from ..identification import identify
    from ..recording import load_recording

    clock = time.perf_counter()
    rec = load_recording(path, **options.reading_for(path))
    row = {"load_s": time.perf_counter() - clock}
    clock = time.perf_counter()
    where = options.network()
    topology = {"topology": where} if options.topology else {}
    result = identify(rec, options.boundary, options.estimator, replicates=options.replicates, **topology)
    row["identify_s"] = time.perf_counter() - clock
    row.update(_identification_columns(result.to_json()))
    for i, f in enumerate(_frequencies_hz(result)):
        row[f"f{i + 1}_hz"] = float(f)
    if options.diagnose:
        clock = time.perf_counter()
        row.update(_diagnosis_columns(diagnosis_json(diagnose(rec, boundary=where))))
        row["diagnose_s"] = time.perf_counter() - clock
    return row


def run_one(path: str, options: Options, done: frozenset = frozenset()) -> dict:
    """The row of the recording at ``path``, or ``{"key", "path", "status": "skipped"}`` when
    its key is in ``done``. Never raises for a bad recording: its row says why."""
    from .. import __version__
    from ..messages import error_text

    clock, cpu = time.perf_counter(), time.process_time()
    p = Path(path)
    row = {"key": None, "path": str(p), "name": p.name, "machine": p.parent.name}
    try:
        row["key"] = content_key(p, options)
        if row["key"] in done:
            return {**row, "status": "skipped"}
        row["recorded_at"] = os.stat(p).st_mtime
        with threads(1):  # a worker per core: the bootstrap's and the candidates' threads would oversubscribe them
            row.update(_analyse(p, options))
        row.update(status="ok", error=None)
    except (Exception, MemoryError) as err:  # noqa: BLE001 - one bad recording never stops the batch
        row.update(status="failed", error=error_text(err))
    row.update(
        task_s=time.perf_counter() - clock,
        cpu_s=time.process_time() - cpu,
        finished_at=time.time(),
        worker_pid=os.getpid(),
        rss_mb=_rss_mb(),
    )
    row["algid_version"] = __version__
    return row
