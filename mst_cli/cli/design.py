"""``mst design``: inverse design from target sensitivities and force ranges (nlopt)."""

from __future__ import annotations

import json
import sys
import time
from pathlib import Path

import click

from mst_cli import api
from mst_cli.cli import help_texts
from mst_cli.cli.common import default_out_dir, handles_input_errors, no_plot_option, out_dir_option, seed_type
from mst_cli.cli.progress import DesignProgress


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
    doc = api.load(spec_file)
    out = out_dir or default_out_dir(doc.name)
    talk = not (quiet or as_json)
    plot = not (no_plot or as_json)
    t_start = time.perf_counter()
    progress = DesignProgress(not talk)
    try:
        run = api.run_design(
            doc,
            pareto=pareto_count,
            pareto_designs=pareto_designs,
            seed=seed,
            max_evaluations=max_evaluations,
            refine=refine,
            calibration=calibration,
            out=out,
            plot=plot,
            progress=progress,
            note=click.echo if talk else None,
            warn=lambda line: click.echo(f"mst design: warning: {line}", err=True),
        )
    finally:
        progress.close()
    result = run.result
    assert result is not None  # run_design solves
    if as_json:
        click.echo(json.dumps(run.report, indent=2, allow_nan=False))
    elif not quiet:
        click.echo(run.summary(out, pareto_designs, plot, time.perf_counter() - t_start))
    if result.exit_code:
        click.echo(f"mst design: targets not met: {result.binding}: {result.reasons[0]}", err=True)
    sys.exit(result.exit_code)
