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

from .messages import error_line


class HelpFormatter(argparse.HelpFormatter):
    """Every subcommand's help alike: an option's default said as ``(default: X)`` unless its
    help says it; paragraphs of a description or epilog filled apart, a line indented by two
    blanks (an example) kept as written."""

    def _get_help_string(self, action: argparse.Action) -> str:
        text = action.help or ""
        unset = action.default is None or action.default is False or action.default in ([], argparse.SUPPRESS)
        if "default" in text or unset or not action.option_strings:
            return text
        return f"{text} (default: %(default)s)"

    def _fill_text(self, text: str, width: int, indent: str) -> str:
        out = []
        for para in text.split("\n\n"):
            lines = para.splitlines()
            if any(line.startswith("  ") for line in lines):
                out.append("\n".join(indent + line for line in lines))
            else:
                out.append(super()._fill_text(para, width, indent))
        return "\n\n".join(out)


#: Options whose value is a comma-separated list (a blank instead of a comma gets a hint).
COMMA_LISTS = ("--force", "--accel", "--velocity", "--displacement", "--units")


def build_parser() -> argparse.ArgumentParser:
    """The argument parser with every subcommand registered."""
    from . import __version__
    from .control import demo
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
    for command in sub.choices.values():
        command.formatter_class = HelpFormatter
    return parser


def _unrecognised(argv: list[str], extras: list[str]) -> str:
    """The error for arguments no option took, with a hint when a blank split a comma list
    (``--force F1 F2``)."""
    text = f"unrecognized arguments: {' '.join(extras)}"
    at = argv.index(extras[0]) if extras[0] in argv else -1
    if at >= 2 and argv[at - 2] in COMMA_LISTS:
        text += f" (a list is comma-separated: {argv[at - 2]} {argv[at - 1]},{extras[0]})"
    return text


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
    argv = sys.argv[1:] if argv is None else list(argv)
    args, extras = parser.parse_known_args(argv)
    command = getattr(args, "command", None)
    if extras:  # said with the subcommand's usage line, not the top level's
        sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
        (sub.choices[command] if command else parser).error(_unrecognised(argv, extras))
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
