"""One-line messages: what every error of the command line and the readers ends in.

An error names the problem in one line of at most :data:`MAX_LINE` characters and quotes
at most about :data:`MAX_QUOTE` characters of the offending input, however large the input
(a 200 MB header line, a column index of ten million digits).
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
