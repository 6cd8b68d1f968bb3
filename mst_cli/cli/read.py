"""``mst read``: MLX90393 readings (a CSV or a live serial stream) -> forces.

Options only: the reading is :mod:`mst_cli.readout.reading` (through :mod:`mst_cli.api`, as a
script would call it).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import click

from mst_cli import api
from mst_cli.cli import help_texts
from mst_cli.cli.calibrate import MECHANICS, fail_fit
from mst_cli.cli.common import default_out_dir, handles_input_errors
from mst_cli.cli.progress import say_rung_solves

BAUD_RATES = (1200, 2400, 4800, 9600, 19200, 38400, 57600, 115200, 230400, 460800, 921600)


@click.command("read")
@click.argument("model_file", type=click.Path(dir_okay=False, path_type=Path))
@click.argument("readings", required=False, type=click.Path(dir_okay=False, path_type=Path))
@click.option("--serial", "port", default=None, metavar="PORT", help=help_texts.READ_SERIAL)
@click.option(
    "--baud",
    type=click.Choice([str(b) for b in BAUD_RATES]),
    default="115200",
    show_default=True,
    help="Baud rate of --serial.",
)
@click.option("--count", type=click.IntRange(min=1), default=None, help=help_texts.READ_COUNT)
@click.option("--timeout", "timeout_s", type=float, default=None, help=help_texts.READ_TIMEOUT)
@click.option("--raw", is_flag=True, help="--serial lines carry raw codes (needs --gain-sel/--res).")
@click.option("--columns", default=None, metavar="MAP", help=help_texts.READ_COLUMNS)
@click.option("--send", default=None, metavar="TEXT", help=help_texts.READ_SEND)
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
@click.option(
    "--estimate", type=click.Choice(api.ESTIMATES), default="none", show_default=True, help=help_texts.READ_ESTIMATE
)
@click.option("--estimate-offset", is_flag=True, help=help_texts.READ_ESTIMATE_OFFSET)
@click.option("--polish", is_flag=True, help=help_texts.READ_POLISH)
@click.option(
    "--max-offset-sigma-mm", type=float, default=1.0, show_default=True, help=help_texts.READ_MAX_OFFSET_SIGMA
)
@click.option("--tare", type=click.IntRange(min=0), default=0, show_default=True, help=help_texts.READ_TARE)
@click.option("--track-zero", is_flag=True, help=help_texts.READ_TRACK_ZERO)
@handles_input_errors
def read(
    model_file: Path,
    readings: Path | None,
    port: str | None,
    baud: str,
    count: int | None,
    timeout_s: float | None,
    raw: bool,
    columns: str | None,
    send: str | None,
    gain_sel: int | None,
    res: int | None,
    mechanics: str | None,
    out_dir: Path | None,
    estimate: str,
    estimate_offset: bool,
    polish: bool,
    max_offset_sigma_mm: float,
    tare: int,
    track_zero: bool,
) -> None:
    """Turn MLX90393 readings into forces with MODEL_FILE (a calibrated.yaml).

    READINGS is a CSV with Bx_uT,By_uT,Bz_uT (or Bx_code_lsb,By_code_lsb,Bz_code_lsb with
    --gain-sel/--res); forces.csv gets the input columns plus force_N, regime, flag and
    force_resolution_N. With --serial PORT an MLX90393 sketch's lines ("X: 12.3 \\tY: -4.5
    \\tZ: 321.0 uTesla", SparkFun's "magX[..] ... temperature(C)[..]", "12.3,-4.5,321.0,24.5",
    ReSkin/AnySkin chips with --columns) are read in batches and shown live, through the same
    steps as a file; with --out forces.csv is the file's, with time_s first.

    Flags: above_calibrated (above the load test's largest force), below_range, above_range
    (past the last lock), saturated (force left empty: never extrapolated). --estimate offset
    adds where each reading was pressed, --estimate shear the tangential force (Fx, Fy).
    """
    estimate = "offset" if estimate_offset else estimate
    _check_sources(readings, port, raw or columns is not None or send is not None, polish, track_zero)
    api.check_argument_order(model_file, readings, "read")
    doc = api.load_design(model_file)
    say_rung_solves("read")
    out = out_dir if (out_dir is not None or port is not None) else default_out_dir(f"{doc.name}-read")
    options: dict[str, Any] = dict(model_file=model_file, mechanics=mechanics, gain_sel=gain_sel, res=res, warn=_warn)
    options.update(estimate=estimate, max_offset_sigma_mm=max_offset_sigma_mm, tare=tare)
    try:
        if readings is not None:
            result = api.read(doc, readings, out=out, polish=polish, track_zero=track_zero, **options)
            click.echo(f"{result.summary()}\nwrote {out}/forces.csv")
            return
        assert port is not None  # one of the two, checked above
        serial = dict(baud=int(baud), count=count, timeout_s=timeout_s, raw=raw, columns=columns, send=send)
        stream = api.read_serial(doc, port, out=out, **serial, **options, **_TERMINAL)  # type: ignore[arg-type]
    except api.CalibrationFailed as exc:
        fail_fit(str(exc), "no inverse map")
    click.echo(stream.line() + "\n" + stream.forces.summary(), err=True)
    if out is not None:
        click.echo(f"wrote {out}/forces.csv", err=True)


def _check_sources(readings: Path | None, port: str | None, raw: bool, polish: bool, track_zero: bool) -> None:
    """A usage error for options that do not go together (``raw``: an option of lines given)."""
    if (readings is None) == (port is None):
        raise click.UsageError("give READINGS.csv or --serial PORT (one of them)")
    if raw and port is None:
        raise click.UsageError("--raw, --columns and --send are for --serial lines (a CSV names its columns)")
    if polish and port is not None:
        raise click.UsageError("--polish reads files, not --serial streams (about 0.1 s a reading)")
    if track_zero and port is not None:
        raise click.UsageError(
            "--track-zero reads files (it finds the rests over the whole record); live, use --tare N"
        )


def _warn(note: str) -> None:
    click.echo(f"mst read: warning: {note}", err=True)


# a live stream's status lines go to stderr, its samples to stdout
_TERMINAL: dict[str, Any] = {"status": lambda line: click.echo(line, err=True), "show": click.echo}
