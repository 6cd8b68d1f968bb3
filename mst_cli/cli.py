"""The ``mst`` command line. Thin: it parses options, calls the library, writes files.

Exit codes (DESIGN.md section 5): 0 success, 1 targets not met / checks failed, 2 invalid
input (one line naming the field, the value and what is allowed). Heavy libraries
(build123d, scikit-fem, matplotlib.pyplot) are imported inside the commands that need them.
"""

from __future__ import annotations

import functools
import json
import sys
from pathlib import Path

import click

from . import __version__

EXIT_TARGETS, EXIT_INPUT = 1, 2  # success is a normal return (0)


def fail_input(message: str) -> None:
    click.echo(f"mst: invalid input: {message}", err=True)
    sys.exit(EXIT_INPUT)


def handles_input_errors(func):
    """Turn :class:`~mst_cli.schema.InputError` into one line on stderr and exit code 2."""
    @functools.wraps(func)
    def wrapper(*args, **kwargs):
        from .schema import InputError
        try:
            return func(*args, **kwargs)
        except InputError as exc:
            fail_input(str(exc))
    return wrapper


def default_out_dir(name: str) -> Path:
    return Path("mst-out") / name


def load_design_document(path):
    """Load a design file and check its cells; InputError on any broken rule."""
    from .schema import InputError, load_document
    doc = load_document(path)
    geometry = doc.geometry()
    for i, v in geometry.violations(doc.printer):
        raise InputError(f"layers[{i}]", {"theta_deg": geometry.layers[i].theta_deg,
                                          "t_mm": geometry.layers[i].t_mm,
                                          "h_mm": geometry.layers[i].h_mm},
                         f"invalid cell ({v.rule}): {v.message}")
    return doc, geometry


def write_simulation(doc, geometry, resp, out_dir: Path, extra_files=None, extra_report=None):
    """report.json, response.csv, response.png (+ extra files) into out_dir, atomically."""
    from .outputs import staged
    from .report import plot_response, report_dict, response_csv

    with staged(out_dir) as st:
        for name, data in (extra_files or {}).items():
            st.write_yaml(name, data)
        st.write_json("report.json", report_dict(doc, geometry, resp, extra_report))
        st.write_text("response.csv", response_csv(resp))
        plot_response(resp, st.path("response.png"), title=doc.name)
    return out_dir


@click.group(context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(__version__, prog_name="mst")
def main():
    """Design multi-sensitivity soft tactile (MST) sensors.

    A stack of collapsible 3D-printed TPU layers, a magnet above it and an MLX90393
    magnetometer below: each layer locks at its own force, so one sensor has several
    sensitivities over several force bands. Units: mm, N, MPa, degrees, mT.

    \b
    mst simulate DESIGN.yaml   forward model: curves, S_i, R_i, field, chip settings
    mst design SPEC.yaml       inverse design from target S_i and R_i to theta, t, h
    mst export DESIGN.yaml     printable STL / STEP of the stacked assembly
    mst check PATH             geometry checks of what export wrote
    mst bench                  measured speed/accuracy table of the models

    Exit codes: 0 success, 1 targets not met or checks failed, 2 invalid input.
    """


@main.command()
@click.argument("design_file", type=click.Path(dir_okay=False, path_type=Path))
@click.option("--out", "out_dir", type=click.Path(file_okay=False, path_type=Path), default=None,
              help="Output folder [default: ./mst-out/<name>/].")
@click.option("--field-model", type=click.Choice(["auto", "dipole", "axial", "cylinder"]), default=None,
              help="Magnet field model [default: the file's model.field, else auto = the cheapest "
                   "exact one: axial on the axis, cylinder off it].")
@click.option("--mechanics", type=click.Choice(["spring", "frame", "continuum"]), default=None,
              help="Layer mechanics model [default: the cheapest whose measured error meets the "
                   "file's model.accuracy_rel, else the file's model.mechanics, else spring].")
@click.option("--json", "as_json", is_flag=True, help="Print report.json to stdout instead of the table.")
@handles_input_errors
def simulate(design_file, out_dir, field_model, mechanics, as_json):
    """Predict force-displacement and field-force curves of DESIGN_FILE.

    Writes report.json (units in keys), response.csv and response.png into the output
    folder and prints a per-regime table: stiffness, force band, secant sensitivity S
    (dB/B0 per newton) with its local min..max, and the force resolution dF of the chip.
    """
    from .ladder import choose_mechanics
    from .report import report_dict, terminal_table
    from .response import simulate as run

    doc, geometry = load_design_document(design_file)
    field_choice = field_model or doc.field_model
    choice = choose_mechanics(mechanics, doc.accuracy_rel, doc.mechanics)
    if choice.message() and not as_json:
        click.echo(choice.message())
    resp = run(geometry, doc.material, mechanics=choice.mechanics,
               field_model=None if field_choice == "auto" else field_choice,
               noise_uT_rms=doc.noise_uT_rms)
    out = out_dir or default_out_dir(doc.name)
    write_simulation(doc, geometry, resp, out)
    if as_json:
        click.echo(json.dumps(report_dict(doc, geometry, resp), indent=2))
    else:
        click.echo(terminal_table(doc, geometry, resp))
        click.echo(f"wrote {out}/report.json, response.csv, response.png")


# Commands that live in their own modules (each keeps its heavy imports inside the command
# function). One add_command line per command, below this comment.
from .cli_export import check, export  # noqa: E402
main.add_command(export)
main.add_command(check)
from .cli_design import design  # noqa: E402
main.add_command(design)
from .cli_bench import bench  # noqa: E402
main.add_command(bench)
from .cli_slice import slice_  # noqa: E402
main.add_command(slice_)
