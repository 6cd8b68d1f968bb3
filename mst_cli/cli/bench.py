"""``mst bench``: the measured speed/accuracy table of the model ladder."""

from __future__ import annotations

from pathlib import Path

import click

from mst_cli.cli.common import default_out_dir, no_plot_option, out_dir_option, seed_type
from mst_cli.io.outputs import staged


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
    """Measure every mechanics rung (spring, frame) and field model against the reference
    (continuum FE; magpylib), and the off-centre tilt rung against L2 under tilted plates, and
    write bench.md, bench.json and bench.png (error vs time; not with --no-plot)."""
    from mst_cli.bench.ladder_bench import bench_markdown, plot_bench, run_bench  # deferred: the model ladder, 0.1 s

    result = run_bench(samples=samples, seed=seed, quick=quick)
    out = out_dir or default_out_dir("bench")
    md = bench_markdown(result)
    with staged(out) as st:
        st.write_json("bench.json", result)
        st.write_text("bench.md", md)
        if no_plot:
            st.remove("bench.png")
        else:
            plot_bench(result, st.path("bench.png"))
    click.echo(md)
    click.echo(f"wrote {out}/bench.md, bench.json" + ("" if no_plot else ", bench.png"))
