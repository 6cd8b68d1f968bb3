"""``mst calibrate``: fit a printed sensor to its load test.

Options only: the calibration and its files are :mod:`mst_cli.calibration.calibration` (through
:mod:`mst_cli.api`, as a script would call it).
"""

from __future__ import annotations

import sys
from pathlib import Path
from typing import NoReturn

import click

from mst_cli import api
from mst_cli.cli import help_texts
from mst_cli.cli.common import (
    EXIT_TARGETS,
    default_out_dir,
    handles_input_errors,
    no_plot_option,
    one_line,
    out_dir_option,
)
from mst_cli.cli.progress import say_rung_solves

MECHANICS = ["spring", "frame", "continuum"]


def fail_fit(reason: str, what: str = "calibration failed") -> NoReturn:
    click.echo(one_line(f"mst: {what}: {reason}; nothing was written"), err=True)
    sys.exit(EXIT_TARGETS)


@click.command()
@click.argument("design_file", type=click.Path(dir_okay=False, path_type=Path))
@click.argument("load_test", type=click.Path(dir_okay=False, path_type=Path))
@out_dir_option("./mst-out/<name>-calibration/")
@click.option(
    "--mechanics",
    type=click.Choice(MECHANICS),
    default="spring",
    show_default=True,
    help="Layer mechanics of the fit: spring is milliseconds per evaluation; frame and "
    "continuum are fitted by space mapping on spring (a few dear evaluations).",
)
@click.option(
    "--params",
    "params",
    default="modulus_factor,wall_offset_mm,gap_offset_mm,remanence_factor",
    show_default=True,
    help="Parameters to fit (comma separated).",
)
@click.option("--gain-sel", type=click.IntRange(0, 7), default=None, help=help_texts.CALIBRATE_GAIN_SEL)
@click.option("--res", type=click.IntRange(0, 3), default=None, help="RES the load test was read at.")
@click.option(
    "--table-size",
    type=click.IntRange(16, 4096),
    default=256,
    show_default=True,
    help="Entries of the lookup table (CSV and C header).",
)
@click.option(
    "--ignore-branches",
    is_flag=True,
    help="Fit every row as loading (default: the loading rows; unloading, holds and a first cycle "
    "that differs are described in calibration.json's hysteresis section, not fitted).",
)
@click.option("--missing-force", type=float, metavar="SENTINEL", help=help_texts.CALIBRATE_MISSING_FORCE)
@click.option(
    "--offset-table",
    is_flag=True,
    help="Also write inverse_table.npz (what mst read --estimate offset reads; a minute or two) and offset_table.h.",
)
@click.option(
    "--shear-table",
    is_flag=True,
    help="Also write shear_table.npz (what mst read --estimate shear reads; about 15 s) and shear_table.h.",
)
@no_plot_option("calibration.png", "about 40 % of a run: 0.45 s of matplotlib import and render", has_json=False)
@handles_input_errors
def calibrate(
    design_file: Path,
    load_test: Path,
    out_dir: Path | None,
    mechanics: str,
    params: str,
    gain_sel: int | None,
    res: int | None,
    table_size: int,
    ignore_branches: bool,
    missing_force: float | None,
    offset_table: bool,
    shear_table: bool,
    no_plot: bool,
) -> None:
    """Fit DESIGN_FILE's print parameters to a LOAD_TEST of the printed sensor.

    LOAD_TEST is a CSV with force_N,Bx_uT,By_uT,Bz_uT (or raw codes Bx_code_lsb,By_code_lsb,
    Bz_code_lsb with --gain-sel/--res). Fits the effective modulus, a wall-thickness offset,
    a magnet-chip gap offset and the remanence; reports which the data cannot identify and
    holds those at the design's values. Writes calibrated.yaml (loadable by mst simulate and
    mst read), calibration.json (values, uncertainties, residuals, S_i and R_i against the
    design's), residuals.csv, lookup.csv, force_table.h (raw Z code -> mN) and
    calibration.png (not with --no-plot). Exit 2 on bad input, 1 when the fit fails (with why); nothing is
    written then.
    """
    names = api.parse_params(params)  # --params is refused before the design is read
    api.check_argument_order(design_file, load_test, "calibrate")
    doc = api.load_design(design_file)
    say_rung_solves("calibrate")
    out = out_dir or default_out_dir(f"{doc.name}-calibration")
    try:
        result = api.calibrate(
            doc,
            load_test,
            out=out,
            plot=not no_plot,
            design_file=design_file,
            mechanics=mechanics,
            params=names,
            gain_sel=gain_sel,
            res=res,
            table_size=table_size,
            offset_table=offset_table,
            shear_table=shear_table,
            progress=lambda line: click.echo(f"mst calibrate: {line}", err=True),
            use_branches=not ignore_branches,
            missing_force=missing_force,
        )
    except api.CalibrationFailed as exc:
        fail_fit(str(exc))
    for warning in result.warnings:
        click.echo(one_line(f"mst calibrate: warning: {warning}"), err=True)
    click.echo(result.summary())
    click.echo(
        f"wrote {out}/{', '.join(result.file_names)}"
        + ("" if no_plot else ", calibration.png")
        + _table_files(offset_table, shear_table, result.header_setting is not None)
        + (f" (no C header: {result.header_reason})" if result.header_reason else "")
    )


def _table_files(offset_table: bool, shear_table: bool, header: bool) -> str:
    """The table files written beside the calibration (a C header each with a chip setting)."""
    kinds = [(k, h) for k, h, asked in (("inverse", "offset", offset_table), ("shear", "shear", shear_table)) if asked]
    return "".join(f", {k}_table.npz" + (f", {h}_table.h" if header else "") for k, h in kinds)
