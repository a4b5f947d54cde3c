"""The ``algid`` command: ``identify``, ``demo``, ``diagnose`` and ``batch``.

Every failure ends in one line on stderr (at most ``algid.messages.MAX_LINE`` characters, quoted
input shortened by ``algid.messages.quote``) and exit code 2; a closed pipe on stdout (``algid ... | head -1``)
ends quietly with 141 as a shell's SIGPIPE would; numerical warnings (numpy's RuntimeWarning)
are counted, not printed. ``ALGID_DEBUG=1`` shows the traceback and the warnings instead.
"""

from __future__ import annotations

import argparse
import os
import sys
import warnings

from .messages import one_line

#: What goes where; the epilog of ``identify --help`` and ``diagnose --help``.
STREAMS = (
    "The summary goes to stdout, progress (on a terminal only) and one-line errors to stderr. "
    "With --json - the JSON goes to stdout and the summary to stderr; --quiet drops the summary."
)


def error_text(err: BaseException) -> str:
    """What went wrong, in one line: the message of an input error, else the exception's type
    and message."""
    if isinstance(err, OSError) and err.strerror:
        what = f"{err.strerror}: {err.filename}" if err.filename else err.strerror
    elif isinstance(err, (ValueError, TypeError)) or type(err).__module__.startswith("algid"):
        what = str(err) or type(err).__name__
    else:
        what = f"{type(err).__name__}: {err}"
    return one_line(what)


def error_line(command: str, err: BaseException) -> str:
    """The one line an exception of ``algid COMMAND`` ends with."""
    return one_line(f"algid {command}: error: {error_text(err)}")


def build_parser() -> argparse.ArgumentParser:
    """The argument parser with every subcommand registered."""
    from . import __version__, demo
    from .diagnosis import cli as diagnosis_cli
    from .fleet import cli as batch_cli
    from .identification import cli as identify_cli

    parser = argparse.ArgumentParser(
        prog="algid", description="On-line algebraic identification of mass-spring-damper chains."
    )
    parser.add_argument("--version", action="version", version=f"algid {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    demo.add_parser(sub)
    identify_cli.add_parser(sub)
    diagnosis_cli.add_parser(sub)
    batch_cli.add_parser(sub)
    return parser


def _run(args: argparse.Namespace) -> int:
    """The subcommand with numerical warnings counted; one line about them unless --quiet."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", RuntimeWarning)
        code = int(args.func(args) or 0)
    numerical = [w for w in caught if issubclass(w.category, RuntimeWarning)]
    for w in caught:
        if not issubclass(w.category, RuntimeWarning):
            warnings.showwarning(w.message, w.category, w.filename, w.lineno)
    if numerical and not getattr(args, "quiet", False):
        print(
            f"algid {args.command}: {len(numerical)} numerical warnings (overflow, invalid value) were handled; "
            "ALGID_DEBUG=1 prints them",
            file=sys.stderr,
        )
    return code


def main(argv: list[str] | None = None) -> int:
    """Run the command line; returns the exit code."""
    parser = build_parser()
    args = parser.parse_args(argv)
    if getattr(args, "func", None) is None:
        parser.print_help()
        return 2
    if os.environ.get("ALGID_DEBUG"):
        return int(args.func(args) or 0)
    try:
        return _run(args)
    except BrokenPipeError:
        # The reader of stdout went away: nothing more to say, and nothing to flush at exit.
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 141
    except KeyboardInterrupt:
        print(f"algid {args.command}: interrupted", file=sys.stderr)
        return 130
    except (Exception, MemoryError) as err:  # noqa: BLE001 - the promise is one line, never a traceback
        print(error_line(args.command, err), file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
