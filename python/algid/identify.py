"""``algid identify``: run the on-line estimator over a recording.

Reads a recording (CSV ``t,u1..un,a1..an`` [s, N, m/s^2], or ``.npz`` with the same names;
displacements ``x1..xn`` [m] instead of accelerations are differentiated, see
:func:`algid.recording.accelerations`), feeds it sample by sample through the C++ estimator
and writes the final eq. 7 estimates as JSON, and optionally the whole history as CSV.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

import numpy as np

from .estimator import ChainEstimator
from .recording import Recording, RecordingError, accelerations, load_recording


class IdentifyError(Exception):
    """A problem to report in one line with exit code 2."""


def identify(rec: Recording, boundary: str = "fixed", progress=None) -> dict:
    """Run the estimator over a whole recording.

    Parameters
    ----------
    rec : validated recording.
    boundary : "fixed" or "free" right end.
    progress : optional callable(fraction in [0, 1]).

    Returns
    -------
    dict with ``t`` (T,) window-end times [s], ``mass`` (T, n) [kg], ``damping`` (T, n)
    [N s/m], ``stiffness`` (T, n+1) [N/m] (fused), ``valid`` (T, n) and ``estimator``.
    """
    accel = accelerations(rec)
    est = ChainEstimator(rec.n, rec.dt, boundary=boundary)
    T = accel.shape[0]
    chunks = np.array_split(np.arange(T), max(1, min(20, T // 20000)))
    parts = []
    for done, idx in enumerate(chunks, start=1):
        if idx.size:
            parts.append(est.run(accel[idx], rec.u[idx]))  # the state carries across chunks
        if progress is not None:
            progress(done / len(chunks))
    out = {key: np.concatenate([p[key] for p in parts]) for key in ("mass", "damping", "stiffness", "valid")}
    out["t"] = rec.t - est.delay_samples * rec.dt
    out["estimator"] = est
    return out


def _json_number(v: float):
    return None if not math.isfinite(v) else float(v)


def final_estimates(result: dict, rec: Recording, boundary: str) -> dict:
    """The JSON document of the final estimates."""
    est: ChainEstimator = result["estimator"]
    valid = [bool(v) for v in est.valid]
    doc = {
        "n": rec.n,
        "mass": [_json_number(v) for v in est.mass],
        "damping": [_json_number(v) for v in est.damping],
        "stiffness": [_json_number(v) for v in est.stiffness],
        "valid": all(valid),
        "valid_dof": valid,
        "boundary": boundary,
        "window_s": est.window,
        "samples": int(rec.t.size),
        "dt_s": rec.dt,
    }
    if rec.n == 1 and boundary == "fixed":
        doc["note"] = "n = 1 with walls: only k1 + k2 is identifiable; it is reported as stiffness[0]"
    if rec.a is None:
        doc["note_accel"] = "accelerations derived from displacements by 5-point differentiation"
    return doc


def write_trace(path: Path, result: dict, n: int, boundary: str) -> None:
    """History CSV ``t,m1..mn,c1..cn,k1..k{n+1},valid`` (n = 1 with walls: k2 empty)."""
    header = ["t"] + [f"m{i + 1}" for i in range(n)] + [f"c{i + 1}" for i in range(n)]
    header += [f"k{j + 1}" for j in range(n + 1)] + ["valid"]
    cols = [result["t"][:, None], result["mass"], result["damping"], result["stiffness"],
            result["valid"].all(axis=1)[:, None].astype(float)]
    table = np.concatenate(cols, axis=1)
    with open(path, "w", encoding="utf-8") as fh:
        fh.write(",".join(header) + "\n")
        for row in table:
            fields = ["" if not math.isfinite(v) else repr(float(v)) for v in row[:-1]]
            fields.append(str(int(row[-1])))
            fh.write(",".join(fields) + "\n")


def add_parser(sub) -> None:
    """Register ``algid identify``."""
    p = sub.add_parser("identify", help="estimate m, c, k of a chain from a recording",
                       description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("recording", type=Path, help="CSV or .npz with t, u1..un, a1..an (or x1..xn)")
    p.add_argument("--json", type=Path, required=True, help="where to write the final estimates")
    p.add_argument("--trace", type=Path, help="optional CSV of the estimate history")
    p.add_argument("--boundary", choices=("fixed", "free"), default="fixed",
                   help="right end: wall (k_{n+1} estimated) or free (k_{n+1} = 0)")
    p.set_defaults(func=run)


def _progress_bar(fraction: float) -> None:
    width = 30
    filled = int(round(width * fraction))
    sys.stderr.write(f"\ridentify [{'#' * filled}{'.' * (width - filled)}] {100 * fraction:5.1f} %")
    if fraction >= 1.0:
        sys.stderr.write("\n")
    sys.stderr.flush()


def run(args) -> int:
    """Entry point of ``algid identify``; returns the exit code."""
    try:
        rec = load_recording(args.recording)
        try:
            result = identify(rec, args.boundary, progress=_progress_bar if sys.stderr.isatty() else None)
        except ValueError as err:  # e.g. a chain size that is not compiled in
            raise IdentifyError(str(err)) from err
        doc = final_estimates(result, rec, args.boundary)
        args.json.write_text(json.dumps(doc, indent=2) + "\n", encoding="utf-8")
        if args.trace is not None:
            write_trace(args.trace, result, rec.n, args.boundary)
    except (RecordingError, IdentifyError) as err:
        print(f"algid identify: error: {err}", file=sys.stderr)
        return 2
    except OSError as err:
        print(f"algid identify: error: {err.strerror}: {err.filename}", file=sys.stderr)
        return 2
    _print_summary(doc)
    return 0


def _print_summary(doc: dict) -> None:
    def fmt(v):
        return "   n/a" if v is None else f"{v:10.5g}"

    print(f"n = {doc['n']}, window {doc['window_s']:.3f} s, valid: {doc['valid']}")
    for i in range(doc["n"]):
        print(f"  DOF {i + 1}: m = {fmt(doc['mass'][i])} kg   c = {fmt(doc['damping'][i])} N s/m")
    for j, k in enumerate(doc["stiffness"]):
        print(f"  spring {j + 1}: k = {fmt(k)} N/m")
