"""``mst calibrate`` (fit a printed sensor to its load test) and ``mst read`` (readings -> forces).

Options only: the calibration and its files are :mod:`mst_cli.calibrate.calibration`, the
reading :mod:`mst_cli.calibrate.reading` (through :mod:`mst_cli.api`, as a script would call them).
"""

from __future__ import annotations

import sys
from pathlib import Path

import click

from mst_cli import api
from mst_cli.cli.common import (
    EXIT_TARGETS,
    default_out_dir,
    handles_input_errors,
    no_plot_option,
    one_line,
    out_dir_option,
)

MECHANICS = ["spring", "frame", "continuum"]
BAUD_RATES = (1200, 2400, 4800, 9600, 19200, 38400, 57600, 115200, 230400, 460800, 921600)


def _fail_fit(reason: str, what: str = "calibration failed") -> None:
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
@click.option(
    "--gain-sel",
    type=click.IntRange(0, 7),
    default=None,
    help="GAIN_SEL the load test was read at (needed for raw codes; the C header's setting).",
)
@click.option("--res", type=click.IntRange(0, 3), default=None, help="RES the load test was read at.")
@click.option(
    "--table-size",
    type=click.IntRange(16, 4096),
    default=256,
    show_default=True,
    help="Entries of the lookup table (CSV and C header).",
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
    doc = api.load_design(design_file)
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
            progress=lambda line: click.echo(f"mst calibrate: {line}", err=True),
        )
    except api.CalibrationFailed as exc:
        _fail_fit(str(exc))
    click.echo(result.summary())
    click.echo(
        f"wrote {out}/{', '.join(result.file_names)}"
        + ("" if no_plot else ", calibration.png")
        + (f" (no C header: {result.header_reason})" if result.header_reason else "")
    )


@click.command("read")
@click.argument("model_file", type=click.Path(dir_okay=False, path_type=Path))
@click.argument("readings", required=False, type=click.Path(dir_okay=False, path_type=Path))
@click.option(
    "--serial",
    "port",
    default=None,
    metavar="PORT",
    help="Read a live stream from this serial port (one sample per line) instead of a file.",
)
@click.option(
    "--baud",
    type=click.Choice([str(b) for b in BAUD_RATES]),
    default="115200",
    show_default=True,
    help="Baud rate of --serial.",
)
@click.option(
    "--count",
    type=click.IntRange(min=1),
    default=None,
    help="Stop --serial after this many samples [default: until the port closes or Ctrl-C].",
)
@click.option(
    "--timeout",
    "timeout_s",
    type=click.FloatRange(min=0.0, min_open=True),
    default=None,
    help="Stop --serial after this many seconds without a byte.",
)
@click.option("--raw", is_flag=True, help="--serial lines carry raw codes (needs --gain-sel/--res).")
@click.option("--gain-sel", type=click.IntRange(0, 7), default=None, help="GAIN_SEL of raw codes.")
@click.option("--res", type=click.IntRange(0, 3), default=None, help="RES of raw codes.")
@click.option(
    "--mechanics",
    type=click.Choice(MECHANICS),
    default=None,
    help="Layer mechanics [default: the model file's model.mechanics].",
)
@click.option(
    "--out",
    "out_dir",
    type=click.Path(file_okay=False, path_type=Path),
    default=None,
    help="Output folder of forces.csv [default: ./mst-out/<name>-read/; with --serial only when given].",
)
@handles_input_errors
def read(
    model_file: Path,
    readings: Path | None,
    port: str | None,
    baud: str,
    count: int | None,
    timeout_s: float | None,
    raw: bool,
    gain_sel: int | None,
    res: int | None,
    mechanics: str | None,
    out_dir: Path | None,
) -> None:
    """Turn MLX90393 readings into forces with MODEL_FILE (a calibrated.yaml).

    READINGS is a CSV with Bx_uT,By_uT,Bz_uT (or Bx_code_lsb,By_code_lsb,Bz_code_lsb with
    --gain-sel/--res); forces.csv gets the input columns plus force_N, regime, flag and
    force_resolution_N. With --serial PORT the lines of an Arduino MLX90393 sketch
    ("X: 12.3 \\tY: -4.5 \\tZ: 321.0 uTesla", "12.3,-4.5,321.0", ...) are shown live
    (and written to forces.csv with --out).

    Flags: above_calibrated (the model's force above the load test's largest force),
    below_range, above_range (past the last lock) and saturated (force left empty: never
    extrapolated).
    """
    if (readings is None) == (port is None):
        raise click.UsageError("give READINGS.csv or --serial PORT (one of them)")
    if raw and port is None:
        raise click.UsageError("--raw is for --serial lines (a CSV says raw by its column names)")
    doc = api.load_design(model_file)
    out = out_dir if (out_dir is not None or port is not None) else default_out_dir(f"{doc.name}-read")
    warn = lambda note: click.echo(f"mst read: warning: {note}", err=True)  # noqa: E731
    try:
        if readings is not None:
            result = api.read(
                doc,
                readings,
                out=out,
                model_file=model_file,
                mechanics=mechanics,
                gain_sel=gain_sel,
                res=res,
                warn=warn,
            )
            click.echo(result.summary())
            click.echo(f"wrote {out}/forces.csv")
            return
        stream = api.read_serial(
            doc,
            port,
            out=out,
            model_file=model_file,
            baud=int(baud),
            count=count,
            timeout_s=timeout_s,
            raw=raw,
            mechanics=mechanics,
            gain_sel=gain_sel,
            res=res,
            warn=warn,
            status=lambda line: click.echo(line, err=True),
            show=click.echo,
        )
    except api.CalibrationFailed as exc:
        _fail_fit(str(exc), "no inverse map")
    click.echo(f"{len(stream.samples)} samples, {stream.skipped} lines skipped (not a sample)", err=True)
    if out is not None:
        click.echo(f"wrote {out}/forces.csv", err=True)
