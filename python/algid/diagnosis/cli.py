"""``algid diagnose RECORDING --json OUT [--plots DIR] [--boundary fixed|free]``.

Registered by the top-level ``algid`` command through :func:`add_parser`. Progress goes to
stderr, the report to stdout; bad input gives one line on stderr and exit code 2.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from ..messages import one_line, quote_path
from ..recording import RecordingError, load_recording
from ..recording.options import add_recording_options, print_notes, recording_options


def add_parser(subparsers) -> argparse.ArgumentParser:
    """Register the ``diagnose`` subcommand on an ``argparse`` subparsers object."""
    p = subparsers.add_parser(
        "diagnose",
        help="locate and explain the gap between a recording and the linear chain",
        description="Fit the linear chain to a recording, locate where it fails (per DOF, time, "
        "frequency, amplitude), fit every candidate unmodelled effect at every location "
        "on training windows, score it on withheld windows and report the best one that "
        "shrinks the gap beyond noise.",
    )
    p.add_argument(
        "recording",
        metavar="RECORDING",
        help="CSV/TSV/TXT (optionally compressed), .npz, HDF5 or UFF 58 with time, u1..un, a1..an (or v, x)",
    )
    p.add_argument("--json", required=True, metavar="OUT", help="where to write the JSON result")
    p.add_argument("--plots", metavar="DIR", help="write the diagnosis figures (PNG) into DIR")
    p.add_argument("--boundary", choices=("fixed", "free"), default="fixed", help="right end of the chain")
    p.add_argument("--quiet", action="store_true", help="no progress and no report on the terminal")
    add_recording_options(p)
    p.set_defaults(func=run)
    return p


def _err(msg: str) -> int:
    print(one_line(f"algid diagnose: error: {msg}"), file=sys.stderr)
    return 2


def run(args: argparse.Namespace) -> int:
    """Execute ``algid diagnose``; returns the exit code (0 ok, 2 bad input)."""
    from .engine import diagnose
    from .report import to_json, to_text

    quiet = bool(getattr(args, "quiet", False))
    tty = sys.stderr.isatty()

    def progress(msg: str) -> None:
        if quiet:
            return
        if tty:  # one status line, rewritten in place
            print(f"\r\033[K[diagnose] {msg}", end="", file=sys.stderr, flush=True)
        elif not msg.startswith("candidate ") or msg.startswith("candidate 1/"):
            print(f"[diagnose] {msg}" + (" ..." if msg.startswith("candidate 1/") else ""), file=sys.stderr, flush=True)

    out = Path(args.json)
    if out.exists() and out.is_dir():
        return _err(f"--json: is a directory: {quote_path(out)}")
    if not out.parent.exists():
        return _err(f"--json: folder does not exist: {quote_path(out.parent)}")
    try:
        rec = load_recording(args.recording, **recording_options(args))
    except RecordingError as err:
        return _err(err)
    print_notes(rec, "diagnose", quiet)
    try:
        d = diagnose(rec, boundary=args.boundary, progress=progress)
    except ValueError as err:
        if not quiet and tty:
            print("\r\033[K", end="", file=sys.stderr, flush=True)
        return _err(f"{Path(args.recording).name}: {err}")
    if not quiet and tty:
        print("\r\033[K", end="", file=sys.stderr, flush=True)
    try:
        out.write_text(json.dumps(to_json(d), indent=1))
    except OSError as err:
        return _err(f"--json {out}: {err.strerror or err}")
    if args.plots:
        try:
            from ..plotting.diagnosis import save_figures

            files = save_figures(d, args.plots)
        except OSError as err:
            return _err(f"--plots {args.plots}: {err.strerror or err}")
        if not quiet:
            print(f"[diagnose] figures: {', '.join(str(f) for f in files)}", file=sys.stderr)
    if not quiet:
        print(to_text(d, source=str(args.recording)))
    return 0
