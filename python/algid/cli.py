"""The ``algid`` command: ``identify``, ``demo`` and ``diagnose``."""

from __future__ import annotations

import argparse
import sys


def build_parser() -> argparse.ArgumentParser:
    """The argument parser with every subcommand registered."""
    from . import __version__, demo
    from .diagnosis import cli as diagnosis_cli
    from .identification import cli as identify_cli

    parser = argparse.ArgumentParser(
        prog="algid", description="On-line algebraic identification of mass-spring-damper chains."
    )
    parser.add_argument("--version", action="version", version=f"algid {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    demo.add_parser(sub)
    identify_cli.add_parser(sub)
    diagnosis_cli.add_parser(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Run the command line; returns the exit code."""
    parser = build_parser()
    args = parser.parse_args(argv)
    if getattr(args, "func", None) is None:
        parser.print_help()
        return 2
    return int(args.func(args) or 0)


if __name__ == "__main__":
    sys.exit(main())
