"""``mst slice``: slice an export with PrusaSlicer and judge whether it prints.

Options only: the run is :mod:`mst_cli.cad.slicing`, the judgement :mod:`mst_cli.cad.print_check`
(through :mod:`mst_cli.api`, as a script would call them).
"""

from __future__ import annotations

import json
import sys
import time
from pathlib import Path

import click

from mst_cli import api
from mst_cli.cli.common import EXIT_FAULT, EXIT_TARGETS, handles_input_errors, no_plot_option, one_line, out_dir_option

DEFAULT_MAX_SPAN_MM = 5.0


@click.command("slice")
@click.argument("path", type=click.Path(path_type=Path))
@click.option(
    "--profile",
    "profile",
    type=click.Path(path_type=Path),
    default=None,
    help="PrusaSlicer config (.ini) [default: the TPU 85A profile shipped with mst, "
    "mst_cli/cad/data/tpu85a-0.4mm.ini].",
)
@out_dir_option("PATH")
@click.option(
    "--max-span",
    "max_span_mm",
    type=float,
    default=DEFAULT_MAX_SPAN_MM,
    show_default=True,
    help="Longest free span allowed (extrusion with nothing under it), mm.",
)
@click.option("--json", "as_json", is_flag=True, help="Print slice.json instead of the summary.")
@click.option(
    "--allow-post-process",
    "allow_post_process",
    is_flag=True,
    help="Let PrusaSlicer run the scripts the profile's post_process names (without it such a profile is refused).",
)
@no_plot_option("print.png", "about 0.8 s: matplotlib and a 3D view of the part", has_json=True)
@handles_input_errors
def slice_(
    path: Path,
    profile: Path | None,
    out_dir: Path | None,
    max_span_mm: float,
    as_json: bool,
    no_plot: bool,
    allow_post_process: bool = False,
) -> None:
    """Slice the body 'mst export' wrote (PATH: its folder) with PrusaSlicer and judge it.

    Slices sensor.3mf (which carries the magnet pause; sensor.stl if there is no 3MF) with the
    profile and writes sensor.gcode, slice.json (print time, filament, layers, longest free
    span and where, the pause found against the one export.json asks for, support, designed
    against as-sliced cavity gaps) and print.png (not with --no-plot). Slices a
    second time with automatic support on to prove that none is needed. Exit 1 naming the
    broken limit (free span over --max-span, pause missing or misplaced, support needed);
    exit 2 when PrusaSlicer is not installed, the profile is not a PrusaSlicer config or
    export.json is malformed (checked before slicing, with mst check's rules); exit 1 when
    PrusaSlicer misbehaves (no G-code, an empty or truncated one). A profile whose post_process
    names scripts is refused (exit 2, naming them) unless --allow-post-process; with it they
    run as PrusaSlicer runs them, one line names them and slice.json lists them (post_process_run).
    """
    t0 = time.perf_counter()

    def progress(message: str) -> None:
        click.echo(f"[{time.perf_counter() - t0:5.2f} s] {message}", err=True)

    plot = not (no_plot or as_json)  # --json implies --no-plot, as on simulate and design
    try:
        result = api.slice(
            path,
            profile=profile,
            out=out_dir,
            max_span_mm=max_span_mm,
            plot=plot,
            progress=progress,
            note=lambda line: click.echo(one_line(f"mst slice: note: {line}"), err=True),
            allow_post_process=allow_post_process,
        )
    except api.SlicerError as exc:
        click.echo(one_line(f"mst slice: {exc}; nothing was written"), err=True)
        sys.exit(EXIT_FAULT)
    progress(f"wrote {out_dir or result.folder}/{', '.join(result.written)}")
    click.echo(json.dumps(result.report, indent=2, allow_nan=False) if as_json else result.summary())
    if result.failed:
        click.echo(f"mst slice: failed: {'; '.join(result.report['reasons'])}", err=True)
        sys.exit(EXIT_TARGETS)
