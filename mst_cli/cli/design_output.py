"""What ``mst design`` prints: the rung and calibration it used, then the design table, the
front's table and the files written (the files themselves: :mod:`mst_cli.design.files`)."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import click

if TYPE_CHECKING:
    from mst_cli.calibrate.calibration_json import PrinterCalibration
    from mst_cli.design.document import DesignResult
    from mst_cli.design.pareto import ParetoDesign
    from mst_cli.model.ladder import MechanicsChoice


def print_design_choices(choice: MechanicsChoice, cal: PrinterCalibration | None) -> None:
    """The mechanics rung picked (and that the L0 design is refined with it), the calibration taken."""
    message = choice.message()
    if message:
        refined = "" if choice.mechanics == "spring" else f": L0 design refined with {choice.mechanics}"
        click.echo(message + refined)
    if cal is not None:
        click.echo("\n".join(cal.lines()))


def print_design_summary(
    result: DesignResult,
    front: list[ParetoDesign] | None,
    pareto_count: int | None,
    pareto_designs: bool,
    out: Path,
    plot: bool,
    seconds: float,
) -> None:
    """The design table, the front's table (if mapped) and the files written, on stdout."""
    click.echo(result.table())
    if front:
        # deferred: loads the model (0.1 s); `mst --help` loads this module
        from mst_cli.design.pareto import front_table

        click.echo(front_table(front))
    elif pareto_count is not None:
        click.echo("Pareto front: not mapped (the targets are not met)")
    files = (
        "design.yaml, report.json, response.csv"
        + (", response.png" if plot else "")
        + (", pareto.csv" + (", pareto.png" if plot else "") if front else "")
        + (f", pareto/ ({len(front)} designs)" if front and pareto_designs else "")
    )
    click.echo(f"wrote {out}/{files} ({seconds:.2f} s)")
