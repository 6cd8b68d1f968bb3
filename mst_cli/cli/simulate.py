"""``mst simulate``: the forward model of one design file, its report, curves and picture."""

from __future__ import annotations

import json
import math
from pathlib import Path

import click

from mst_cli import api
from mst_cli.cli.common import default_out_dir, handles_input_errors, no_plot_option, out_dir_option
from mst_cli.cli.progress import say_rung_solves
from mst_cli.errors import InputError


@click.command()
@click.argument("design_file", type=click.Path(dir_okay=False, path_type=Path))
@out_dir_option()
@click.option(
    "--field-model",
    type=click.Choice(["auto", "dipole", "axial", "cylinder"]),
    default=None,
    help="Magnet field model [default: the file's model.field, else auto = the cheapest "
    "exact one: axial on the axis, cylinder off it].",
)
@click.option(
    "--mechanics",
    type=click.Choice(["spring", "frame", "continuum"]),
    default=None,
    help="Layer mechanics model [default: the cheapest whose measured error meets the "
    "file's model.accuracy_rel, else the file's model.mechanics, else spring].",
)
@click.option(
    "--json", "as_json", is_flag=True, help="Print report.json to stdout instead of the table (implies --no-plot)."
)
@click.option(
    "--load-offset-mm",
    "load_offset",
    metavar="X,Y",
    default=None,
    help="Press off the axis, at X,Y mm on the top face (x across the width, y along the depth): "
    "adds offcentre.csv/.png and report.json's off_centre (each layer's lock on each side, the "
    "magnet's tilt, and how far a reading taken as axial is off).",
)
@click.option(
    "--shear-ratio",
    "shear_ratio",
    metavar="RX,RY",
    default=None,
    help="Push along the face as well: a tangential force Fx = RX x F, Fy = RY x F along the "
    "curve (each |R| <= 1), at the axis or at --load-offset-mm; offcentre.csv gets its Fx_N, Fy_N.",
)
@click.option(
    "--press-width-mm",
    "press_width_mm",
    type=float,
    default=api.FINGERTIP_PATCH_MM,
    help="Width of the press's contact patch, a centred strip across the depth, mm (0 < W <= the face's "
    "width), a fingertip by default: sets how much the cap bends in report.json's load_path "
    "(docs/design.md 4.6).",
    show_default=True,
)
@click.option(
    "--offset-map",
    is_flag=True,
    help="Add offset_map.csv/.png: the axial reading's force error over 80 % of the top face at "
    "25, 50, 75 % of every regime (about 10 s).",
)
@no_plot_option("response.png", "about 2/3 of a run: 0.45 s of matplotlib import and render")
@handles_input_errors
def simulate(
    design_file: Path,
    out_dir: Path | None,
    field_model: str | None,
    mechanics: str | None,
    as_json: bool,
    load_offset: str | None,
    shear_ratio: str | None,
    press_width_mm: float,
    offset_map: bool,
    no_plot: bool,
) -> None:
    """Predict force-displacement and field-force curves of DESIGN_FILE.

    Writes report.json (units in keys), response.csv and response.png (not with --no-plot
    or --json) into the output folder and prints a per-regime table: stiffness, force band,
    secant sensitivity S (dB/B0 per newton) with its local min..max, and the force
    resolution dF of the chip. The part is simulated as printed: walls + printer.wall_offset_mm,
    modulus x printer.modulus_factor, gap + printer.gap_offset_mm (a design made with
    mst design --calibration carries them; they are 0, 1, 0 by default).
    """
    doc = api.load_design(design_file)
    say_rung_solves("simulate")
    out = out_dir or default_out_dir(doc.name)
    plot = not (no_plot or as_json)
    run = api.run_simulate(
        doc,
        mechanics=mechanics,
        field_model=field_model,
        load_offset_mm=_pair(load_offset, "--load-offset-mm", "X,Y in mm, e.g. 5,0")
        if load_offset is not None
        else None,
        shear_ratio=_pair(shear_ratio, "--shear-ratio", "RX,RY, e.g. 0.3,0") if shear_ratio is not None else None,
        offset_map=offset_map,
        out=out,
        plot=plot,
        note=None if as_json else click.echo,
        press_width_mm=press_width_mm,
    )
    if as_json:
        click.echo(json.dumps(run.report, indent=2, allow_nan=False))
        return
    click.echo(run.table())
    click.echo(f"wrote {out}/" + ", ".join(run.file_names(plot)))


def _pair(text: str, option: str, form: str) -> tuple[float, float]:
    """'A,B' as two finite floats (InputError naming ``option`` otherwise)."""
    parts = text.split(",")
    try:
        x, y = (float(p) for p in parts)
    except ValueError:
        raise InputError(option, text, f"must be two numbers {form}") from None
    if not all(map(math.isfinite, (x, y))):
        raise InputError(option, text, f"must be two finite numbers {form}")
    return x, y
