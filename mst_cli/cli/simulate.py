"""``mst simulate``: the forward model of one design file, its report, curves and picture."""

from __future__ import annotations

import json
from pathlib import Path
from typing import TYPE_CHECKING

import click

from mst_cli import api
from mst_cli.cli.common import default_out_dir, handles_input_errors, no_plot_option, out_dir_option
from mst_cli.io.outputs import check_out_dir

if TYPE_CHECKING:
    from mst_cli.io.schema import Document


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
@no_plot_option("response.png", "about 2/3 of a run: 0.45 s of matplotlib import and render")
@handles_input_errors
def simulate(
    design_file: Path,
    out_dir: Path | None,
    field_model: str | None,
    mechanics: str | None,
    as_json: bool,
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
    from mst_cli.calibrate.fit import PRINTER_NOMINAL
    from mst_cli.io.report import terminal_table, write_simulation
    from mst_cli.io.schema import load_design_document
    from mst_cli.model.ladder import choose_mechanics

    doc, geometry = load_design_document(design_file)
    out = out_dir or default_out_dir(doc.name)
    check_out_dir(out)  # a bad output path is refused before any work
    if not as_json:
        _say_model_choices(doc, choose_mechanics(mechanics, doc.accuracy_rel, doc.mechanics).message())
    resp = api.simulate(doc, mechanics=mechanics, field_model=field_model)
    plot = not (no_plot or as_json)
    as_printed = {f"printer.{k}": getattr(doc.printer, k) for k in PRINTER_NOMINAL}
    report = write_simulation(doc, geometry, resp, out, plot=plot, extra_report={"as_printed": as_printed})
    if as_json:
        click.echo(json.dumps(report, indent=2, allow_nan=False))
    else:
        click.echo(terminal_table(doc, geometry, resp))
        click.echo(f"wrote {out}/report.json, response.csv" + (", response.png" if plot else ""))


def _say_model_choices(doc: Document, mechanics_message: str | None) -> None:
    """The mechanics rung picked for the file, and the print parameters that differ from nominal."""
    from mst_cli.calibrate.fit import PRINTER_NOMINAL  # deferred: as simulate's

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
