"""The files ``mst design`` (and :func:`mst_cli.api.design`'s callers) write for a design result:
design.yaml, report.json, response.csv/png and, with a Pareto front, pareto.csv/png and its designs."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

from mst_cli.simulation.report import write_simulation

if TYPE_CHECKING:
    from mst_cli.calibration.calibration_json import PrinterCalibration
    from mst_cli.design.pareto import ParetoDesign
    from mst_cli.design.result import DesignResult
    from mst_cli.io.outputs import Staging


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
    if not front:
        st.remove("pareto.csv")
        st.remove("pareto.png")
        return
    from mst_cli.design.pareto import pareto_csv, plot_pareto  # deferred: the front's layer, only with one

    st.write_text("pareto.csv", pareto_csv(front))
    if plot:
        plot_pareto(front, st.path("pareto.png"), title=title)
    else:
        st.remove("pareto.png")
