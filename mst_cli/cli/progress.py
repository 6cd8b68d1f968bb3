"""The progress line of the long-running commands (``mst design``), on stderr."""

from __future__ import annotations

import math
import sys
import time

import click

from mst_cli import api
from mst_cli.cli.common import one_line

RUNG_PHASE = "the whole-part rung"  # the phase of mst_cli.design.document's section rounds


def say_rung_solves(verb: str) -> None:
    """On stderr, before a section-mode model (``model.load_path: section``) solves the whole-part
    rung afresh: seconds each, which a user should hear about before they start."""
    api.tell_rung_solves(lambda line: click.echo(one_line(f"mst {verb}: {line}"), err=True))


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
        self.phase = ""

    def __call__(self, done: int, total: int, phase: str, worst_err: float) -> None:
        if self.quiet:
            return
        now = time.monotonic()
        # a new phase is said at once: the whole-part rung's rounds are few and long
        new_phase, self.phase = phase != self.phase, phase
        if now - self.t0 < 1.0 or (not new_phase and now - self.last < (0.2 if self.tty else 5.0)):
            return
        self.last = now
        width = 24
        fill = int(width * done / max(total, 1))
        worst = f"worst error {100 * worst_err:.2f} %" if math.isfinite(worst_err) else "no candidate yet"
        if phase.startswith(RUNG_PHASE):  # design.document's section rounds count designs, not evaluations
            line = f"mst design: [{'#' * fill}{'.' * (width - fill)}] {phase} of at most {total}"
        else:
            line = f"mst design: [{'#' * fill}{'.' * (width - fill)}] {done}/{total} evaluations, {phase}, {worst}"
        if self.tty:
            click.echo("\r" + line, err=True, nl=False)
            self.shown = True
        else:
            click.echo(line, err=True)

    def close(self) -> None:
        if self.shown:
            click.echo("", err=True)
