"""The progress line of the long-running commands (``mst design``), on stderr."""

from __future__ import annotations

import math
import sys
import time

import click


class DesignProgress:
    """A compact progress line on stderr: live on a terminal, a line every few seconds otherwise.

    Short runs (the usual case, well under a second) print nothing.
    """

    def __init__(self, quiet: bool):
        self.quiet = quiet
        self.tty = sys.stderr.isatty()
        self.t0 = time.monotonic()
        self.last = self.t0
        self.shown = False

    def __call__(self, done: int, total: int, phase: str, worst_err: float) -> None:
        if self.quiet:
            return
        now = time.monotonic()
        if now - self.t0 < 1.0 or now - self.last < (0.2 if self.tty else 5.0):
            return
        self.last = now
        width = 24
        fill = int(width * done / max(total, 1))
        worst = f"worst error {100 * worst_err:.2f} %" if math.isfinite(worst_err) else "no candidate yet"
        line = f"mst design: [{'#' * fill}{'.' * (width - fill)}] {done}/{total} evaluations, {phase}, {worst}"
        if self.tty:
            click.echo("\r" + line, err=True, nl=False)
            self.shown = True
        else:
            click.echo(line, err=True)

    def close(self) -> None:
        if self.shown:
            click.echo("", err=True)
