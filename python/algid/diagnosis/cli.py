"""``algid diagnose RECORDING [--json OUT|-] [--plots DIR] [--model OUT] [--boundary fixed|free]``.

Registered by the top-level ``algid`` command through :func:`add_parser`. The report goes
to stdout (to stderr with ``--json -``, which puts the JSON on stdout), progress (on a
terminal only, :class:`algid.messages.progress.Progress`) to stderr; bad input gives one line on
stderr and exit code 2.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from ..messages import STREAMS, example, one_line, quote_path
from ..messages.progress import Progress
from ..model.network import Network
from ..recording import RecordingError, load_recording
from ..recording.options import RECORDING_HELP, add_recording_options, print_notes, recording_options
from ..recording.transient import add_band_option


def add_parser(subparsers) -> argparse.ArgumentParser:
    """Register the ``diagnose`` subcommand on an ``argparse`` subparsers object."""
    p = subparsers.add_parser(
        "diagnose",
        help="locate and explain the gap between a recording and the linear chain",
        description="Fit the linear chain to a recording, locate where it fails (per DOF, time, "
        "frequency, amplitude), fit every candidate unmodelled effect at every location "
        "on training windows, score it on withheld windows and report the best one that "
        "shrinks the gap beyond noise.",
        epilog=f"{STREAMS}\n\n{example('algid diagnose rig.csv --force F1 --accel acc1 --plots figures/')}",
    )
    p.add_argument(
        "recording",
        metavar="RECORDING",
        help=RECORDING_HELP,
    )
    p.add_argument("--json", metavar="OUT", help="write the JSON result to OUT ('-': stdout)")
    p.add_argument("--plots", metavar="DIR", help="write the diagnosis figures (PNG) into DIR")
    p.add_argument(
        "--model",
        metavar="OUT",
        help="write the chain refitted with the reported effect to OUT (JSON that algid.Chain.from_json reads; "
        "with --topology the network, read by algid.NetworkModel.from_json)",
    )
    p.add_argument("--boundary", choices=("fixed", "free"), default="fixed", help="right end of the chain")
    p.add_argument(
        "--topology",
        metavar="NET.json",
        help='a spring network {"n": N, "springs": [[a, b], ...]} (0 = ground) instead of the chain',
    )
    p.add_argument("--quiet", action="store_true", help="no progress and no report on the terminal")
    add_band_option(p)
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
    progress = Progress("diagnose", quiet=quiet)
    out = None if args.json in (None, "-") else Path(args.json)
    if out is not None and out.is_dir():
        return _err(f"--json: is a directory: {quote_path(out)}")
    if out is not None and not out.parent.exists():
        return _err(f"--json: folder does not exist: {quote_path(out.parent)}")
    try:
        rec = load_recording(args.recording, **recording_options(args))
    except RecordingError as err:
        return _err(err)
    print_notes(rec, "diagnose", quiet)
    try:
        boundary = args.boundary
        if getattr(args, "topology", None):
            if args.boundary != "fixed":
                return _err("--topology describes every spring: no --boundary with it")
            boundary = Network.from_json(args.topology)
        d = diagnose(rec, boundary=boundary, progress=progress.message, band_hz=args.band)
    except ValueError as err:
        return _err(f"{Path(args.recording).name}: {err}")
    finally:
        progress.close()
    if out is not None:
        try:
            out.write_text(json.dumps(to_json(d), indent=1))
        except OSError as err:
            return _err(f"--json {out}: {err.strerror or err}")
    if args.model:
        from .corrected import corrected_model
        from .report import json_safe

        model = corrected_model(d)
        if model is None:
            kind = "network" if getattr(args, "topology", None) else "chain"
            print(f"algid diagnose: --model: no effect reported, the linear {kind} is the model", file=sys.stderr)
        else:
            try:
                Path(args.model).write_text(json.dumps(json_safe(model), indent=1))
            except OSError as err:
                return _err(f"--model {args.model}: {err.strerror or err}")
    if args.plots:
        try:
            from ..plotting.diagnosis import save_figures

            files = save_figures(d, args.plots)
        except OSError as err:
            return _err(f"--plots {args.plots}: {err.strerror or err}")
        if not quiet:
            print(f"[diagnose] figures: {', '.join(str(f) for f in files)}", file=sys.stderr)
    if args.json == "-":
        print(json.dumps(to_json(d), indent=1))
    if not quiet:
        print(to_text(d, source=str(args.recording)), file=sys.stderr if args.json == "-" else sys.stdout)
    return 0
