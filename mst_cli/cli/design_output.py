"""The files ``mst design`` writes and the summary it prints, from a design result and its front.

(Design logic that a later step may move into :mod:`mst_cli.design` or the API; the command
module :mod:`mst_cli.cli.design` keeps only its options and the calls.)
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

import click

if TYPE_CHECKING:
    from mst_cli.calibrate.record import PrinterCalibration
    from mst_cli.design.document import DesignResult
    from mst_cli.design.pareto import ParetoDesign
    from mst_cli.io.outputs import Staging
    from mst_cli.model.ladder import MechanicsChoice


def print_design_choices(choice: MechanicsChoice, cal: PrinterCalibration | None) -> None:
    """The mechanics rung picked (and that the L0 design is refined with it), the calibration taken."""
    message = choice.message()
    if message:
        refined = "" if choice.mechanics == "spring" else f": L0 design refined with {choice.mechanics}"
        click.echo(message + refined)
    if cal is not None:
        click.echo("\n".join(cal.lines()))


def write_design_files(
    result: DesignResult,
    front: list[ParetoDesign] | None,
    cal: PrinterCalibration | None,
    out: Path,
    pareto_count: int | None,
    pareto_designs: bool,
    plot: bool,
    name: str,
) -> dict:
    """design.yaml, the report files and, with a front, pareto.csv/png (and its designs); returns
    report.json's dict. Without a front an older run's front files are removed."""
    from mst_cli.io.report import write_simulation  # deferred: loads the model (0.1 s); `mst --help` loads this module

    extra = result.report_extra()
    if cal is not None:
        extra["design"]["calibration"] = cal.report()
    extra_files: dict[str, Any] = {"design.yaml": result.design_yaml_dict()}
    if front:
        names = [f"pareto/design-{k + 1:02d}.yaml" for k in range(len(front))] if pareto_designs else []
        files = ["pareto.csv"] + (["pareto.png"] if plot else []) + names
        extra["pareto"] = {"designs": len(front), "requested": pareto_count, "files": files}
        extra_files.update({n: p.result.design_yaml_dict() for n, p in zip(names, front)})
    title = f"{name}: designs that meet every target"
    return write_simulation(
        result.document,
        result.geometry,
        result.response,
        out,
        extra_files=extra_files,
        extra_report=extra,
        more=lambda st: _write_front(st, front, plot, title),
        plot=plot,
    )


def _write_front(st: Staging, front: list[ParetoDesign] | None, plot: bool, title: str) -> None:
    """pareto.csv and pareto.png of a front (no picture without ``plot``); without a front an
    older run's files are removed."""
    from mst_cli.design.pareto import pareto_csv, plot_pareto  # deferred: the design package is 0.1 s

    if not front:
        st.remove("pareto.csv")
        st.remove("pareto.png")
        return
    st.write_text("pareto.csv", pareto_csv(front))
    if plot:
        plot_pareto(front, st.path("pareto.png"), title=title)
    else:
        st.remove("pareto.png")


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
