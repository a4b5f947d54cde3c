"""``algid batch INPUTS... --out DIR [--diagnose] [--workers N] [--topology NET.json] [reading options]
[--layouts FILE]``.

Every recording the inputs name (files, folders, glob patterns) read with the options of
``algid identify`` (``--force``, ``--accel``, ``--units``, ``--rate``...; per glob pattern from
``--layouts``), identified, and with ``--diagnose`` diagnosed, on Dask: an embedded
``LocalCluster`` of ``--workers`` processes, or the cluster of ``--scheduler tcp://host:port``.
Writes ``DIR/results/part-*.parquet`` (one row per recording, resumable), ``DIR/summary.csv`` (one row per machine) and
``DIR/histories.png``, ``DIR/verdicts.png``. With ``--topology`` every recording is identified (and
diagnosed) on that spring network, as ``algid identify --topology``; ``--boundary`` and
``--estimator`` are the chain's and refused with it. A progress bar on a terminal; the failed
recordings (at most :data:`SHOWN_FAILURES`) and the count ok / failed / skipped on stderr.
Exit codes: 0 when the batch ran (failed recordings are rows with their error), 3 when no
recording could be used, 2 on bad input.
"""

from __future__ import annotations

import logging
import sys
from pathlib import Path

from ..identification.plan import ESTIMATORS
from ..identification.surrogate import REPLICATES
from ..recording.options import add_recording_options, given_options, mapping_file, reading_options
from .engine import PART_ROWS

#: Failed recordings named on stderr; the rest are in the results' ``error`` column.
SHOWN_FAILURES = 10
#: How long to wait for a scheduler given by --scheduler.
CONNECT_TIMEOUT = "20s"


DESCRIPTION = (
    "Identify, and with --diagnose diagnose, every recording of the inputs on Dask; one Parquet row per "
    "recording in DIR/results, a per-machine summary and plots. A rerun skips the recordings already "
    "done (same content, version and options)."
)


def add_parser(sub) -> None:
    """Register ``algid batch``."""
    summary = "identify (and diagnose) folders of recordings on Dask, results to Parquet"
    from ..messages import example

    epilog = example("algid batch rigs/ --out results/ --force F1 --accel acc1 --units acceleration=g")
    p = sub.add_parser("batch", help=summary, description=DESCRIPTION, epilog=epilog)
    p.add_argument("inputs", nargs="+", metavar="INPUT", help="recording files, folders or glob patterns")
    p.add_argument(
        "--out", type=Path, required=True, metavar="DIR", help="output folder (created; resumed if it exists)"
    )
    p.add_argument("--diagnose", action="store_true", help="also diagnose every recording (algid diagnose)")
    p.add_argument("--scheduler", metavar="ADDRESS", help="run on this Dask scheduler (tcp://host:port)")
    p.add_argument("--workers", type=int, metavar="N", help="processes of the embedded cluster (default: cores)")
    p.add_argument("--boundary", choices=("fixed", "free"), default="fixed", help="right end of the chain")
    p.add_argument("--estimator", choices=ESTIMATORS, default="auto", help="as algid identify --estimator")
    p.add_argument("--replicates", type=int, default=REPLICATES, metavar="N", help="bootstrap replicates")
    p.add_argument(
        "--topology",
        type=Path,
        metavar="NET.json",
        help='a spring network {"n": N, "springs": [[a, b], ...]} (0 = ground) every recording is identified (and '
        "diagnosed) on, as algid identify --topology; not with --boundary or --estimator",
    )
    p.add_argument("--part-rows", type=int, default=PART_ROWS, metavar="N", help="rows per Parquet part")
    p.add_argument("--quiet", action="store_true", help="no progress, no summary")
    add_recording_options(p)
    p.add_argument(
        "--layouts",
        type=Path,
        metavar="FILE",
        help="for folders of mixed layouts: a JSON or TOML file mapping glob patterns to the options above, "
        'e.g. {"rig_a/*.csv": {"force": "F1", "accel": "acc1", "units": "acceleration=g"}}; a file takes the '
        "first pattern that matches it, over the command line's options",
    )
    p.set_defaults(func=run)


def _bar(quiet: bool):
    """A tqdm bar over recordings on a terminal; None elsewhere."""
    if quiet or not sys.stderr.isatty():
        return None
    from tqdm import tqdm

    return tqdm(unit="rec", file=sys.stderr, dynamic_ncols=True)


def _report(table, out: Path, quiet: bool) -> None:
    from ..plotting.batch import save_figures
    from .summary import summary

    per_machine = summary(table)
    per_machine.to_csv(out / "summary.csv", index=False)
    save_figures(table, out)
    if not quiet:
        print(per_machine.to_string(index=False))


def _topology(args):
    """The network of ``--topology`` (None without it); a one-line ``ValueError`` with a chain's option."""
    if args.topology is None:
        return None
    from ..identification.network import refuse_chain_options
    from ..model.network import Network

    refuse_chain_options(args.boundary, args.estimator)
    return Network.from_json(args.topology)


def run(args) -> int:
    """Entry point of ``algid batch``; returns the exit code."""
    from ..messages import error_line
    from .deps import require
    from .engine import batch
    from .inputs import read_layouts

    for flag, value in (("--workers", args.workers), ("--part-rows", args.part_rows)):
        if value is not None and value < 1:
            print(error_line("batch", ValueError(f"{flag} must be >= 1, got {value}")), file=sys.stderr)
            return 2
    reading = given_options(args)
    try:
        if "columns" in reading:
            reading["columns"] = mapping_file(reading["columns"])
        reading_options(**reading)  # bad options fail here, before a worker starts
        topology = _topology(args)
        layouts = read_layouts(args.layouts) if args.layouts is not None else None
    except (ValueError, OSError) as err:
        print(error_line("batch", err), file=sys.stderr)
        return 2
    require()
    logging.getLogger("distributed").setLevel(logging.ERROR)
    bar = _bar(args.quiet)

    def progress(counts: dict, total: int) -> None:
        bar.total = total
        bar.update(1)
        bar.set_postfix(counts, refresh=False)

    options = {"diagnose": args.diagnose, "boundary": args.boundary, "estimator": args.estimator, "topology": topology}
    options.update(replicates=args.replicates, part_rows=args.part_rows, progress=progress if bar is not None else None)
    options.update(reading=reading, layouts=layouts)
    try:
        if args.scheduler:
            from distributed import Client

            with Client(args.scheduler, timeout=CONNECT_TIMEOUT) as client:
                table = batch(args.inputs, args.out, client, **options)
        else:
            table = batch(args.inputs, args.out, workers=args.workers, **options)
    finally:
        if bar is not None:
            bar.close()
    failed = table[table["status"] == "failed"]
    for _, row in failed.head(SHOWN_FAILURES).iterrows():
        print(f"algid batch: {row['error']}", file=sys.stderr)
    if len(failed) > SHOWN_FAILURES:
        print(f"algid batch: ... and {len(failed) - SHOWN_FAILURES} more failed (column 'error')", file=sys.stderr)
    _report(table, args.out, args.quiet)
    counts = table.attrs["counts"]
    print(
        f"algid batch: {counts['ok']} ok, {counts['failed']} failed, {counts['skipped']} skipped; "
        f"results in {args.out / 'results'}",
        file=sys.stderr,
    )
    return 3 if counts["ok"] + counts["skipped"] == 0 else 0
