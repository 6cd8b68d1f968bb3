"""``mst simulate``: the forward model of one design file, its report, curves and picture."""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import TYPE_CHECKING

import click

from mst_cli import api
from mst_cli.cli.common import default_out_dir, handles_input_errors, no_plot_option, out_dir_option
from mst_cli.io.outputs import check_out_dir

if TYPE_CHECKING:
    from mst_cli.sensor.document import Document


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
    # deferred: `mst --help` loads every command module; these load the model (0.1 s)
    from mst_cli.model.ladder import choose_mechanics
    from mst_cli.sensor.as_printed import PRINTER_NOMINAL  # deferred: as simulate's
    from mst_cli.sensor.document import load_design_document
    from mst_cli.simulation.offcentre_files import offcentre_lines, offcentre_summary, write_offcentre
    from mst_cli.simulation.report import terminal_table, write_simulation

    doc, geometry = load_design_document(design_file)
    out = out_dir or default_out_dir(doc.name)
    check_out_dir(out)  # a bad output path is refused before any work
    if not as_json:
        _say_model_choices(doc, choose_mechanics(mechanics, doc.accuracy_rel, doc.mechanics).message())
    resp = api.simulate(doc, mechanics=mechanics, field_model=field_model)
    plot = not (no_plot or as_json)
    extra: dict = {"as_printed": {f"printer.{k}": getattr(doc.printer, k) for k in PRINTER_NOMINAL}}
    off = (
        api.simulate_offcentre(doc, _offset(load_offset), mechanics=mechanics, field_model=field_model)
        if load_offset
        else None
    )
    omap = api.offset_map(doc, mechanics=mechanics, field_model=field_model) if offset_map else None
    if off is not None:
        extra["off_centre"] = offcentre_summary(off)  # the report's and the terminal's
    report = write_simulation(
        doc, geometry, resp, out, plot=plot, extra_report=extra, more=lambda st: write_offcentre(st, off, omap, plot)
    )
    if as_json:
        click.echo(json.dumps(report, indent=2, allow_nan=False))
        return
    click.echo(terminal_table(doc, geometry, resp))
    if off is not None:
        click.echo("\n".join(offcentre_lines(extra["off_centre"])))
    names = ["report.json", "response.csv"] + (["response.png"] if plot else [])
    for stem, present in (("offcentre", off), ("offset_map", omap)):
        names += [f"{stem}.csv"] + ([f"{stem}.png"] if plot else []) if present is not None else []
    click.echo(f"wrote {out}/" + ", ".join(names))


def _offset(text: str) -> tuple[float, float]:
    """'X,Y' in mm as two finite floats (InputError otherwise)."""
    from mst_cli.errors import InputError  # deferred: as simulate's

    parts = text.split(",")
    try:
        x, y = (float(p) for p in parts)
    except ValueError:
        raise InputError("--load-offset-mm", text, "must be two numbers X,Y in mm, e.g. 5,0") from None
    if not all(map(math.isfinite, (x, y))):
        raise InputError("--load-offset-mm", text, "must be two finite numbers X,Y in mm")
    return x, y


def _say_model_choices(doc: Document, mechanics_message: str | None) -> None:
    """The mechanics rung picked for the file, and the print parameters that differ from nominal."""
    from mst_cli.sensor.as_printed import PRINTER_NOMINAL  # deferred: as simulate's

    if mechanics_message:
        click.echo(mechanics_message)
    pr = doc.printer
    deviations = {key: getattr(pr, key) for key in PRINTER_NOMINAL if getattr(pr, key) != PRINTER_NOMINAL[key]}
    if deviations:
        click.echo(
            "as printed: "
            + ", ".join(f"printer.{k} = {v:g}" for k, v in deviations.items())
            + " (the walls drawn are the file's t_mm)"
        )
