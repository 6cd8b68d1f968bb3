"""``mst bench``: the measured speed/accuracy table of the model ladder."""

from __future__ import annotations

from pathlib import Path

import click

from mst_cli import api
from mst_cli.cli.common import default_out_dir, no_plot_option, out_dir_option, seed_type


@click.command()
@click.option(
    "--samples",
    type=click.IntRange(min=1, max=500),
    default=24,
    show_default=True,
    help="Number of seeded valid designs across the bounds.",
)
@click.option("--seed", type=seed_type(), default=0, show_default=True, help="Random seed of the sample.")
@out_dir_option("./mst-out/bench/")
@click.option("--quick", is_flag=True, help="Skip the L2 mesh-convergence study and the tilt rung's check.")
@no_plot_option("bench.png", "about 0.5 s of matplotlib import and render", has_json=False)
def bench(samples: int, seed: int, out_dir: Path | None, quick: bool, no_plot: bool) -> None:
    """Measure the model ladder against its references and write bench.md, bench.json and
    bench.png (error vs time; not with --no-plot).

    The mechanics rungs (spring, frame) against continuum FE on seeded designs (stiffness and
    lock force, time per layer), the field models against magpylib, the continuum mesh's
    convergence, and the off-centre tilt rung against L2 under tilted plates (the last two
    not with --quick)."""
    out = out_dir or default_out_dir("bench")
    result = api.bench(samples=samples, seed=seed, quick=quick, out=out, plot=not no_plot)
    click.echo(result.markdown())
    click.echo(f"wrote {out}/bench.md, bench.json" + ("" if no_plot else ", bench.png"))
