"""Progress of long work on stderr, the one helper of every command (``demo``, ``identify``,
``diagnose``).

On a terminal a tqdm bar per stage (``[identify] window length  42%|####  |``), cleared when
the stage ends; when stderr is not a terminal (a log file, a pipe, CI) or with ``quiet``
nothing at all, so logs hold only what the command says on purpose.
"""

from __future__ import annotations

import sys
from typing import TextIO

#: Steps of a bar (a fraction is shown in whole percent).
STEPS = 100


class Progress:
    """``progress(stage, fraction)`` callback of a command called ``command``.

    ``fraction`` in [0, 1] moves the bar of ``stage``; ``None`` shows the stage without a
    fraction (work of unknown length). A new stage replaces the previous bar.
    """

    def __init__(self, command: str, quiet: bool = False, stream: TextIO | None = None) -> None:
        self.command = command
        self.stream = stream if stream is not None else sys.stderr
        tty = bool(getattr(self.stream, "isatty", lambda: False)())
        self.active = tty and not quiet
        self._stage: str | None = None
        self._bar = None

    def __call__(self, stage: str, fraction: float | None = None) -> None:
        if not self.active:
            return
        if stage != self._stage:
            self.close()
            self._stage = stage
            self._bar = self._new_bar(stage, fraction is not None)
        if fraction is not None:
            self._bar.n = round(STEPS * min(max(float(fraction), 0.0), 1.0))
        self._bar.refresh()

    def _new_bar(self, stage: str, counted: bool):
        from tqdm import tqdm

        return tqdm(
            total=STEPS if counted else None,
            desc=f"[{self.command}] {stage}",
            file=self.stream,
            leave=False,
            dynamic_ncols=True,
            bar_format="{l_bar}{bar}| {elapsed}" if counted else "{desc} {elapsed}",
        )

    def fraction(self, stage: str):
        """A ``callback(fraction)`` for work that reports only a fraction (the simulator)."""
        return lambda fraction: self(stage, fraction)

    def message(self, text: str) -> None:
        """Show ``text`` as a stage of unknown length (a message-style progress callback)."""
        self(text, None)

    def close(self) -> None:
        """End the current bar and clear its line (terminal only)."""
        if self._bar is not None:
            self._bar.close()
            self._bar, self._stage = None, None
