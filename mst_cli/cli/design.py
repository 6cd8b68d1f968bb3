"""``mst design``: inverse design from target sensitivities and force ranges (nlopt)."""

from __future__ import annotations

import json
import sys
import time
from pathlib import Path
from typing import TYPE_CHECKING

import click

from mst_cli import api
from mst_cli.cli import help_texts
from mst_cli.cli.common import default_out_dir, handles_input_errors, no_plot_option, out_dir_option, seed_type
from mst_cli.cli.design_output import print_design_choices, print_design_summary
from mst_cli.cli.progress import DesignProgress
from mst_cli.errors import InputError
from mst_cli.io.outputs import check_out_dir

if TYPE_CHECKING:
    from mst_cli.design.document import DesignResult
    from mst_cli.design.pareto import ParetoDesign
    from mst_cli.model.ladder import MechanicsChoice
    from mst_cli.sensor.document import Document


@click.command(help=help_texts.DESIGN)
@click.argument("spec_file", type=click.Path(dir_okay=False, path_type=Path))
@out_dir_option()
@click.option(
    "--seed",
    type=seed_type(),
    default=None,
    help="Seed of the random starts [default: the file's design.seed, else 0]. "
    "Same spec and seed give a byte-identical design.yaml.",
)
@click.option(
    "--max-evaluations",
    type=click.IntRange(min=10),
    default=None,
    help="Budget of candidate evaluations [default: design.max_evaluations, else 20000].",
)
@click.option(
    "--refine",
    type=click.Choice(["frame", "continuum"]),
    default=None,
    help=help_texts.DESIGN_REFINE,
)
@click.option(
    "--pareto",
    "pareto_count",
    type=click.IntRange(min=2, max=60),
    default=None,
    metavar="N",
    help=help_texts.DESIGN_PARETO,
)
@click.option(
    "--calibration",
    "calibration",
    type=click.Path(dir_okay=False, path_type=Path),
    default=None,
    metavar="CAL/calibration.json",
    help=help_texts.DESIGN_CALIBRATION,
)
@click.option(
    "--pareto-designs", is_flag=True, help="With --pareto: also write every front design as pareto/design-NN.yaml."
)
@click.option("--quiet", "-q", is_flag=True, help="No table and no progress; exit code and files only.")
@click.option(
    "--json", "as_json", is_flag=True, help="Print report.json to stdout instead of the table (implies --no-plot)."
)
@no_plot_option(
    "response.png or pareto.png", "about half of a run on the reference spec: 0.45 s of matplotlib import and render"
)
@handles_input_errors
def design(
    spec_file: Path,
    out_dir: Path | None,
    seed: int | None,
    max_evaluations: int | None,
    refine: str | None,
    pareto_count: int | None,
    calibration: Path | None,
    pareto_designs: bool,
    quiet: bool,
    as_json: bool,
    no_plot: bool,
) -> None:
    # deferred: `mst --help` loads every command module; these load the model (0.1 s)
    from mst_cli.calibrate.calibration_json import load_with_calibration
    from mst_cli.design.files import write_design_files

    doc, cal = load_with_calibration(spec_file, calibration)
    out = out_dir or default_out_dir(doc.name)
    check_out_dir(out)  # a bad output path: refused before any work
    choice = _mechanics_choice(doc, refine, pareto_count, pareto_designs)
    talk = not (quiet or as_json)
    if talk:
        print_design_choices(choice, cal)
    t_start = time.perf_counter()
    result, front = _solve(doc, refine, pareto_count, seed, max_evaluations, DesignProgress(not talk))
    plot = not (no_plot or as_json)
    report = write_design_files(result, front, cal, out, pareto_count, pareto_designs, plot, doc.name)
    if as_json:
        click.echo(json.dumps(report, indent=2, allow_nan=False))
    elif not quiet:
        print_design_summary(result, front, pareto_count, pareto_designs, out, plot, time.perf_counter() - t_start)
    if result.exit_code:
        click.echo(f"mst design: targets not met: {result.binding}: {result.reasons[0]}", err=True)
    sys.exit(result.exit_code)


def _mechanics_choice(
    doc: Document, refine: str | None, pareto_count: int | None, pareto_designs: bool
) -> MechanicsChoice:
    """The rung the design is judged by; the options that cannot go together are refused."""
    from mst_cli.model.ladder import choose_mechanics  # deferred: as above

    if pareto_designs and pareto_count is None:
        raise InputError("--pareto-designs", True, "needs --pareto N")
    choice = choose_mechanics(refine, doc.accuracy_rel, doc.mechanics)
    if pareto_count is not None and choice.mechanics != "spring":
        raise InputError(
            "--pareto",
            pareto_count,
            f"maps the front with the L0 spring model; drop "
            f"--refine/model.accuracy_rel (asked for {choice.mechanics}) or refine one "
            f"front design afterwards with --pareto-designs and mst design --refine",
        )
    return choice


def _solve(
    doc: Document,
    refine: str | None,
    pareto_count: int | None,
    seed: int | None,
    max_evaluations: int | None,
    progress: DesignProgress,
) -> tuple[DesignResult, list[ParetoDesign] | None]:
    """(the design result, the Pareto front or None) through the library's API."""
    try:
        if pareto_count is not None:
            return api.pareto(doc, pareto_count, seed=seed, max_evaluations=max_evaluations, progress=progress)
        return api.design(doc, seed=seed, max_evaluations=max_evaluations, refine=refine, progress=progress), None
    finally:
        progress.close()
