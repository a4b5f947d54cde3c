"""Progress of long work on stderr, the same for every command.

On a terminal one status line is rewritten in place (``\\r``) once a stage has run for
:data:`SHOW_AFTER_S`; anywhere else (a log file, a pipe, CI) a stage that took longer than
that prints one line when it ends, so logs stay readable and quick work prints nothing.
``quiet`` prints nothing.
"""

from __future__ import annotations

import sys
import time
from typing import TextIO

#: Stages shorter than this [s] print nothing.
SHOW_AFTER_S = 1.0


class Progress:
    """``progress(stage, fraction)`` callback for a command called ``command``."""

    def __init__(self, command: str, quiet: bool = False, stream: TextIO | None = None) -> None:
        self.command = command
        self.quiet = bool(quiet)
        self.stream = stream if stream is not None else sys.stderr
        self.tty = bool(getattr(self.stream, "isatty", lambda: False)())
        self._stage: str | None = None
        self._t0 = time.perf_counter()
        self._shown = -1

    def __call__(self, stage: str, fraction: float) -> None:
        if self.quiet:
            return
        if stage != self._stage:
            self._stage, self._t0, self._shown = stage, time.perf_counter(), -1
        elapsed = time.perf_counter() - self._t0
        pct = int(100 * min(max(fraction, 0.0), 1.0))
        if self.tty and elapsed >= SHOW_AFTER_S and pct != self._shown:
            self.stream.write(f"\r\033[K[{self.command}] {stage} {pct:3d} %")
            self._shown = pct
        elif not self.tty and fraction >= 1.0 and elapsed >= SHOW_AFTER_S and self._shown < 100:
            self.stream.write(f"[{self.command}] {stage} done in {elapsed:.1f} s\n")
            self._shown = 100
        self.stream.flush()

    def close(self) -> None:
        """Clear the status line (terminal only)."""
        if self.tty and not self.quiet:
            self.stream.write("\r\033[K")
            self.stream.flush()
