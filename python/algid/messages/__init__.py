"""One-line messages: what every error of the command line and the readers ends in, and the
text every subcommand shares (its examples, where its output goes).

An error names the problem in one line of at most :data:`MAX_LINE` characters and quotes
at most about :data:`MAX_QUOTE` characters of the offending input, however large the input
(a 200 MB header line, a column index of ten million digits).

The rest of what algid says to a person is beside it: :mod:`.display` (how objects show
themselves), :mod:`.progress` (progress of long work on stderr) and :mod:`.deprecation`
(old names that still work and say which name replaced them). The subcommands take their
shared text from here, so no library module imports the command line (:mod:`algid.cli`).
"""

from __future__ import annotations

MAX_LINE = 200  # [characters] of an error line
MAX_QUOTE = 80  # [characters] of the offending input quoted in it


def quote(text: object, limit: int = MAX_QUOTE) -> str:
    """``repr`` of a piece of offending input, shortened to about ``limit`` characters."""
    s = str(text)
    r = repr(s if len(s) <= limit else s[: limit - 3] + "...")
    # repr spells a control character or a lone surrogate in 4-6 characters (NUL: \\x00)
    return r if len(r) <= limit + 2 else r[: limit - 2] + "..." + r[-1]


def quote_path(path: object, limit: int = MAX_QUOTE) -> str:
    """A path shortened from the left to about ``limit`` characters (its end names the file)."""
    s = str(path)
    return s if len(s) <= limit else "..." + s[-(limit - 3) :]


def one_line(message: object, limit: int = MAX_LINE) -> str:
    """The message on one line (whitespace collapsed) of at most ``limit`` characters."""
    s = " ".join(str(message).split())
    return s if len(s) <= limit else s[: limit - 3] + "..."


def listing(names: list[str], most: int = 5) -> str:
    """``a, b, c`` for a few names, ``a, b, c, d, e and 9995 more`` for many."""
    shown = ", ".join(names[:most])
    return shown if len(names) <= most else f"{shown} and {len(names) - most} more"


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


#: What goes where; the epilog of ``identify --help`` and ``diagnose --help``.
STREAMS = (
    "The summary goes to stdout, progress (on a terminal only) and one-line errors to stderr. "
    "With --json - the JSON goes to stdout and the summary to stderr; --quiet drops the summary."
)


def example(*lines: str) -> str:
    """The epilog paragraph of a subcommand's examples: ``example:`` and each command line."""
    return "example:\n" + "\n".join(f"  {line}" for line in lines)
