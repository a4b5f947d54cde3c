"""``algid identify RECORDING [--json OUT|-] [--trace CSV] [--plots DIR] [--estimator ...] [--effect NAME[:LOC] ...]``.

Estimates every mass, damping and spring of the chain in a recording with one standard
deviation each, says of every estimate whether it is valid and, if not, why
(:func:`algid.identify`), and gives the modes of the estimated chain (natural frequency and
damping ratio with one standard deviation, :mod:`algid.model.modal`); with ``--effect``, the
chain and the effect's parameters estimated together (:mod:`.augmented`). The table goes to stdout
(to stderr with ``--json -``, which puts the JSON on stdout), one line per invalid estimate
and the progress to stderr. Exit codes: 0 when something was identified (invalid entries
carry their reasons), 3 when nothing in the recording is identifiable, 2 on bad input.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

from ..messages import STREAMS, error_line, example, quote_path
from ..messages.progress import Progress
from ..model.chain import Chain
from ..recording import RecordingError, load_recording
from ..recording.frf_file import is_frf_source
from ..recording.options import RECORDING_HELP, add_recording_options, print_notes, recording_options
from ..recording.transient import add_band_option
from .plan import ESTIMATORS
from .surrogate import REPLICATES


class IdentifyError(Exception):
    """A problem to report in one line with exit code 2."""


def add_parser(sub) -> None:
    """Register ``algid identify``."""
    p = sub.add_parser(
        "identify",
        help="estimate m, c, k of a chain from a recording, with uncertainties",
        description="Estimate every mass, damping and spring of the chain in a recording, with "
        "one standard deviation each and a verdict (valid, or why not), and the modes of the "
        "estimated chain (natural frequency, damping ratio). The estimator is chosen from the "
        "recording unless --estimator says otherwise.",
        epilog=f"{STREAMS}\n\n{example('algid identify rig.csv --force F1 --accel acc1 --units acceleration=g')}",
    )
    p.add_argument(
        "recording",
        type=Path,
        metavar="RECORDING",
        help=RECORDING_HELP + "; with a support motion a0 (v0, x0) for base excitation, forces then optional; "
        "or FRFs: UFF 58 of function type 4, or .npz with frequency_hz, frf, quantity (docs/identify.md)",
    )
    p.add_argument(
        "--json",
        type=Path,
        metavar="OUT",
        help="write the estimates, uncertainties, verdicts and modes as JSON to OUT ('-': stdout)",
    )
    p.add_argument("--trace", type=Path, metavar="CSV", help="write the estimate history (with sigma_ columns) as CSV")
    p.add_argument(
        "--plots",
        type=Path,
        metavar="DIR",
        help="write estimates.png (histories with one-sigma bands; with --effect, prediction.png: the chain with "
        "the effect against the linear one and the data) and frf.png (model vs H1 of the recording); on an impact "
        "record transient.png (the hits, the decay and the identified chain's response to the force); for FRFs "
        "frf_fit.png (model vs measured FRFs)",
    )
    p.add_argument(
        "--resolution",
        type=float,
        metavar="HZ",
        help="bin width of frf.png's H1 estimate (default: half the narrowest half-power bandwidth of the "
        "estimated modes, as far as the record allows)",
    )
    p.add_argument(
        "--boundary",
        choices=("fixed", "free"),
        default="fixed",
        help="right end: wall (k_{n+1} estimated) or free (k_{n+1} = 0)",
    )
    p.add_argument(
        "--estimator",
        choices=ESTIMATORS,
        default="auto",
        help="single growing window, continuous windows, or chosen from the recording",
    )
    p.add_argument(
        "--replicates",
        type=int,
        metavar="N",
        default=REPLICATES,
        help="bootstrap replicates for the uncertainties",
    )
    p.add_argument(
        "--effect",
        action="append",
        default=[],
        metavar="NAME[:LOCATION]",
        help="estimate this unmodelled effect with the chain (repeatable; the names and locations of "
        "`algid diagnose`: coulomb_friction:1 is dry friction at DOF 1, cubic_stiffness:2 a cubic spring "
        "2); 'auto' takes the effect the diagnosis reports",
    )
    p.add_argument(
        "--topology",
        type=Path,
        metavar="NET.json",
        help='a spring network {"n": N, "springs": [[a, b], ...]} (0 = ground) instead of the chain: '
        "identified by the windowed equation-error fit",
    )
    p.add_argument("--quiet", action="store_true", help="no progress and no summary")
    add_band_option(p)
    add_recording_options(p)
    p.set_defaults(func=run)


def _check_output(path: Path, flag: str) -> None:
    if path.is_dir():
        raise IdentifyError(f"{flag}: is a directory: {quote_path(path)}")
    if not path.parent.exists():
        raise IdentifyError(f"{flag}: folder does not exist: {quote_path(path.parent)}")


def run(args) -> int:
    """Entry point of ``algid identify``; returns the exit code."""
    from .engine import identify

    progress = Progress("identify", quiet=args.quiet)
    try:
        for path, flag in ((args.json, "--json"), (args.trace, "--trace")):
            if path is not None and not (flag == "--json" and str(path) == "-"):
                _check_output(path, flag)
        if args.replicates < 2:
            raise IdentifyError(f"--replicates must be >= 2, got {args.replicates}")
        if args.resolution is not None and not args.resolution > 0:
            raise IdentifyError(f"--resolution must be > 0 Hz, got {args.resolution:g}")
        if is_frf_source(args.recording):
            result, rec = _identify_frf(args), None
        else:
            rec = load_recording(args.recording, **recording_options(args))
            print_notes(rec, "identify", args.quiet)
            try:
                result = identify(
                    rec,
                    args.boundary,
                    args.estimator,
                    replicates=args.replicates,
                    progress=progress,
                    effects=args.effect,
                    band_hz=args.band,
                    **({"topology": args.topology} if args.topology is not None else {}),
                )
            except ValueError as err:  # e.g. a configuration the estimator rejects
                raise IdentifyError(str(err)) from err
            finally:
                progress.close()
        if args.json is not None and str(args.json) != "-":
            args.json.write_text(json.dumps(result.to_json(), indent=2) + "\n", encoding="utf-8")
        if args.trace is not None:
            result.write_trace(args.trace)
        if args.plots is not None:
            _write_figures(result, rec, args.plots, progress, args.resolution)
    except (RecordingError, IdentifyError) as err:
        print(error_line("identify", err), file=sys.stderr)
        return 2
    except OSError as err:
        print(error_line("identify", err), file=sys.stderr)
        return 2
    screened = getattr(result, "screened", None)  # FRFs have no samples to screen
    for line in ([screened.line()] if screened is not None and screened.count else []) + result.reasons:
        print(f"algid identify: {line}", file=sys.stderr)
    to_stdout = args.json is not None and str(args.json) == "-"
    if to_stdout:
        print(json.dumps(result.to_json(), indent=2))
    if not args.quiet:
        print(result.summary(), file=sys.stderr if to_stdout else sys.stdout)
    if not result.identified_any:
        print("algid identify: nothing in this recording is identifiable", file=sys.stderr)
        return 3
    return 0


def _identify_frf(args):
    """The FRF fit of ``args.recording`` (:func:`algid.identification.frf_fit.identify_frf`)."""
    from .frf_fit import identify_frf

    if args.trace is not None or args.effect or args.estimator != "auto":
        raise IdentifyError("--trace, --effect and --estimator apply to time recordings, not to FRFs")
    try:
        result = identify_frf(args.recording, args.boundary)
    except ValueError as err:  # RecordingError included
        raise IdentifyError(str(err)) from err
    print_notes(result.data, "identify", args.quiet)
    return result


def _write_figures(result, rec, folder: Path, progress: Progress, resolution: float | None = None) -> None:
    """``estimates.png`` and ``frf.png`` (the estimated chain's FRF, if it has one, against
    the recording's H1 in bins of ``resolution`` [Hz], by default fine enough for the
    estimated modes: :func:`algid.model.frf.resolution_hz`); for FRFs (``rec`` None)
    ``frf_fit.png``, the model against them."""
    from ..model.frf import recording_h1, resolution_hz
    from ..plotting.frf import save_frf, save_frf_fit
    from ..plotting.identify import save_figures

    progress("writing figures", None)
    if rec is None:
        save_frf_fit(result, folder)
        progress.close()
        return
    try:
        save_figures(result, folder)
        modal, _ = result.modes()
        chain = None
        if modal is not None:  # a network's modes come with the table; its FRF plot shows the record's H1
            chain = None if result.network else Chain.from_packed(result.theta, result.n, result.boundary)
        if resolution is None and chain is not None:
            resolution = resolution_hz(chain)
        save_frf(recording_h1(rec, resolution=resolution), folder, chain)
        if result.transient is not None:
            from ..plotting.transient import save_transient

            save_transient(result, rec, folder)
    finally:
        progress.close()
