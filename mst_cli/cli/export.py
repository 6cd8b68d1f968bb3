"""``mst export`` and ``mst check``: the printable body and its geometry checks.

manifold3d (the STL and 3MF meshes, and the checks) and build123d (CAD: only for --step) are
imported inside the commands, so that importing :mod:`mst_cli.cli.app` stays cheap.
"""

from __future__ import annotations

import json
import sys
import time
from pathlib import Path

import click

from mst_cli import api
from mst_cli.cli.common import EXIT_TARGETS, handles_input_errors, out_dir_option

DEFAULT_STL_TOLERANCE_MM = 0.01  # cad.exporting's (the command line imports only the api)


def _progress(t0: float, message: str) -> None:
    click.echo(f"[{time.perf_counter() - t0:5.2f} s] {message}", err=True)


@click.command("export")
@click.argument("path", type=click.Path(dir_okay=False, path_type=Path))
@click.option("--stl", "want_stl", is_flag=True, help="Write sensor.stl (the one printable TPU body).")
@click.option(
    "--step", "want_step", is_flag=True, help="Write sensor.step: assembly of the body, the magnet and the board."
)
@click.option("--3mf", "want_3mf", is_flag=True, help="Write sensor.3mf (the body, mm).")
@out_dir_option()
@click.option(
    "--stl-tolerance",
    "stl_tolerance_mm",
    type=float,
    default=DEFAULT_STL_TOLERANCE_MM,
    show_default=True,
    help="Largest chord deviation of the mesh from the curved surfaces (the magnet pocket), mm.",
)
@handles_input_errors
def export(
    path: Path, want_stl: bool, want_step: bool, want_3mf: bool, out_dir: Path | None, stl_tolerance_mm: float
) -> None:
    """Build the printable sensor of the design file PATH and write it.

    PATH may also be a spec (targets only): it is designed first, as 'mst design' does, and
    the design is written next to the body as design.yaml (exit 1 if the targets are not met;
    the nearest design is still exported). Without a format flag, writes STL and STEP. Always
    writes export.json: the design's own expected volume, bounding box, pocket, slot and
    feature sizes, which 'mst check' reads.
    STL and 3MF are in print orientation: the part lies on its side (sensor -y face on the
    bed), so every layer is a prism along the build direction and nothing needs support. The
    3MF carries PrusaSlicer's pause for the magnet; the terminal and export.json give its
    layer and height. STEP is the assembly in the sensor frame (z up the stack).
    """
    if not (want_stl or want_step or want_3mf):
        want_stl = want_step = True
    t0 = time.perf_counter()
    files = api.export(
        path,
        out_dir,
        stl=want_stl,
        step=want_step,
        three_mf=want_3mf,
        stl_tolerance_mm=stl_tolerance_mm,
        progress=lambda message: _progress(t0, message),
    )
    note = files.tilt_note()
    if note:
        click.echo(note, err=True)
    click.echo(files.summary(want_3mf))
    designed = files.designed
    if designed is not None and designed.exit_code:
        click.echo(
            f"mst export: targets not met ({designed.binding}: {designed.reasons[0]}); "
            "the body of the nearest design was written",
            err=True,
        )
        sys.exit(designed.exit_code)


@click.command("check")
@click.argument("path", type=click.Path(path_type=Path))
@click.option("--json", "as_json", is_flag=True, help="Print the results as JSON instead of the table.")
@click.option(
    "--nozzle",
    "nozzle_mm",
    type=float,
    default=None,
    help="Nozzle diameter for the wall checks, mm [default: the design's printer.nozzle_mm].",
)
@click.option(
    "--load-path-max",
    type=float,
    default=None,
    help="Fail the load_path check when more than this share (0-1) of the magnet's motion under a "
    "centred press lies outside the layers (cap, plates, cover) in any regime, naming the member "
    "[default: fail when the share the closed form leaves uncertain, simply supported against "
    "clamped, exceeds the regime's accuracy budget: 5 % before the first lock, 8 % after one, 20 % "
    "after two]. docs/design.md 4.6.",
)
@click.option(
    "--whole-part",
    is_flag=True,
    help="Also solve the part's section as exported on the whole-part rung (plane strain, every member as "
    "printed) and fail where its field change per newton at the chip differs from the design's own linear "
    "figure (like for like: report.json load_path.regimes[].field_change_small_load_uT_per_N; the secant S is "
    "shown beside it) by more than the regime's budget (5 / 8 / 20 %), naming the member the closed form "
    "misses. Two solves a regime, three more where it fails; two more a regime for a report (never failing) "
    "of the turn per off-centre moment and the slide and turn per tangential newton in each regime against "
    "mst's general load: seconds to a few minutes the first time, the solves kept in mst's cache. "
    "docs/design.md 4.7.",
)
@handles_input_errors
def check(path: Path, as_json: bool, nozzle_mm: float | None, load_path_max: float | None, whole_part: bool) -> None:
    """Check the body that 'mst export' wrote (PATH: its folder, or the STL in it).

    Prints a table of named checks, measured on the mesh against the design's own expected
    values in export.json. Exit 1 naming the failed checks, 2 for unreadable input.
    """
    t0 = time.perf_counter()
    results = api.check(
        path,
        nozzle_mm=nozzle_mm,
        load_path_max=load_path_max,
        whole_part=whole_part,
        progress=lambda message: _progress(t0, message),
    )
    if as_json:
        click.echo(json.dumps(results.to_dict(), indent=2, allow_nan=False))
    else:
        click.echo(results.table())
    if results.failed:
        click.echo(f"mst check: failed: {', '.join(results.failed)}", err=True)
        sys.exit(EXIT_TARGETS)
