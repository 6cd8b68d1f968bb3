"""``mst design``: inverse design from target sensitivities and force ranges (nlopt)."""

from __future__ import annotations

import json
import math
import sys
import time
from pathlib import Path

import click

from mst_cli.cli.common import (
    default_out_dir,
    handles_input_errors,
    no_plot_option,
    out_dir_option,
    seed_type,
    write_simulation,
)


class _Progress:
    """A compact progress line on stderr: live on a terminal, a line every few seconds otherwise.

    Short runs (the usual case, well under a second) print nothing.
    """

    def __init__(self, quiet: bool):
        self.quiet = quiet
        self.tty = sys.stderr.isatty()
        self.t0 = time.monotonic()
        self.last = self.t0
        self.shown = False

    def __call__(self, done, total, phase, worst_err):
        if self.quiet:
            return
        now = time.monotonic()
        if now - self.t0 < 1.0 or now - self.last < (0.2 if self.tty else 5.0):
            return
        self.last = now
        width = 24
        fill = int(width * done / max(total, 1))
        worst = f"worst error {100 * worst_err:.2f} %" if math.isfinite(worst_err) else "no candidate yet"
        line = f"mst design: [{'#' * fill}{'.' * (width - fill)}] {done}/{total} evaluations, {phase}, {worst}"
        if self.tty:
            click.echo("\r" + line, err=True, nl=False)
            self.shown = True
        else:
            click.echo(line, err=True)

    def close(self):
        if self.shown:
            click.echo("", err=True)


@click.command()
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
    help="Polish the L0 optimum with a dearer mechanics model (output space mapping: "
    "L0 targets corrected by the dear model's miss, L0 re-solved, repeated); every "
    "achieved number then comes from that model [default: model.accuracy_rel's "
    "pick, else model.mechanics if not spring, else no refinement].",
)
@click.option(
    "--pareto",
    "pareto_count",
    type=click.IntRange(min=2, max=60),
    default=None,
    metavar="N",
    help="Also map the trade among designs that meet the targets: up to N non-dominated "
    "designs over total height, worst force resolution and print robustness, "
    "written to pareto.csv (one design per row, units in the header) and "
    "pareto.png, the chosen one (design.objective's weights) marked.",
)
@click.option(
    "--calibration",
    "calibration",
    type=click.Path(dir_okay=False, path_type=Path),
    default=None,
    metavar="CAL/calibration.json",
    help="Design for the printer as an earlier print measured it: take the wall offset, modulus "
    "factor, gap offset and remanence that mst calibrate fitted on a print of any design "
    "(same printer and filament) into printer.* and magnet.remanence_T; parameters the "
    "calibration held are not used, and named.",
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
    """Find theta, t, h of every layer so that the sensor meets SPEC_FILE's targets.

    Per layer the spec gives a target sensitivity S (dB/B0 per newton, secant over the
    regime) and the force R at which that layer locks (the regime's end). Three variables
    per layer meet two targets; the spare freedom picks, among the designs that meet them,
    the one that minimises the spec's design.objective: a weighted sum of total height,
    worst force resolution and print robustness (how much S and R change when every wall is
    printed printer.wall_tolerance_mm off, default 0.05 mm; reported per layer, with the worst
    change beside the RMS). --pareto N maps the trade. The walls are designed as printed
    (printer.wall_offset_mm, printer.modulus_factor; --calibration takes them from an earlier
    print) and design.yaml draws them as drawn. Every achieved number comes from re-running
    the forward model on the written design as printed.

    Writes design.yaml (loadable by mst simulate and mst export), report.json,
    response.csv and response.png (not with --no-plot or --json).

    With --refine frame|continuum (or model.accuracy_rel asking for a dearer rung, or
    model.mechanics: frame|continuum) the fast L0 optimum is polished for that model and the
    targets are judged by it; report.json's refinement section lists the iterations.

    \b
    Exit codes:
      0  every target within the tolerance (design.tolerance_rel, default 2 %)
      1  physically unreachable: the nearest design is written and the binding
         target or constraint is named (field change the magnet cannot give,
         forces outside what printable walls reach, S rising with force, ...)
      2  invalid or self-contradictory spec (e.g. ranges that do not increase)
    """
    from mst_cli.io.outputs import check_out_dir

    doc, cal = _spec_with_calibration(spec_file, calibration)
    out = out_dir or default_out_dir(doc.name)
    check_out_dir(out)  # a bad output path: refused before any work
    choice = _mechanics_choice(doc, refine, pareto_count, pareto_designs)
    talk = not (quiet or as_json)
    if choice.message() and talk:
        click.echo(
            choice.message() + ("" if choice.mechanics == "spring" else f": L0 design refined with {choice.mechanics}")
        )
    if cal is not None and talk:
        click.echo("\n".join(cal.lines()))
    t_start = time.perf_counter()
    result, front = _solve(doc, refine, pareto_count, seed, max_evaluations, _Progress(not talk))
    plot = not (no_plot or as_json)
    report = _write(result, front, cal, out, pareto_count, pareto_designs, plot, doc.name)
    if as_json:
        click.echo(json.dumps(report, indent=2, allow_nan=False))
    elif not quiet:
        _print_summary(result, front, pareto_count, pareto_designs, out, plot, time.perf_counter() - t_start)
    if result.exit_code:
        click.echo(f"mst design: targets not met: {result.binding}: {result.reasons[0]}", err=True)
    sys.exit(result.exit_code)


def _spec_with_calibration(spec_file: Path, calibration: Path | None) -> tuple:
    """The spec, with an earlier print's calibration applied (and that calibration, or None)."""
    from mst_cli.io.schema import load_document

    doc = load_document(spec_file)
    if calibration is None:
        return doc, None
    from mst_cli.calibrate.record import apply_calibration, read_calibration

    cal = read_calibration(calibration, doc)
    return apply_calibration(doc, cal), cal


def _mechanics_choice(doc, refine: str | None, pareto_count: int | None, pareto_designs: bool):
    """The rung the design is judged by; the options that cannot go together are refused."""
    from mst_cli.errors import InputError
    from mst_cli.model.ladder import choose_mechanics

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
    doc,
    refine: str | None,
    pareto_count: int | None,
    seed: int | None,
    max_evaluations: int | None,
    progress: _Progress,
) -> tuple:
    """(the design result, the Pareto front or None) through the library's API."""
    from mst_cli import api

    try:
        if pareto_count is not None:
            return api.pareto(doc, pareto_count, seed=seed, max_evaluations=max_evaluations, progress=progress)
        return api.design(doc, seed=seed, max_evaluations=max_evaluations, refine=refine, progress=progress), None
    finally:
        progress.close()


def _write(
    result, front, cal, out: Path, pareto_count: int | None, pareto_designs: bool, plot: bool, name: str
) -> dict:
    """design.yaml, the report files and, with a front, pareto.csv/png (and its designs); returns
    report.json's dict. Without a front an older run's front files are removed."""
    extra = result.report_extra()
    if cal is not None:
        extra["design"]["calibration"] = cal.report()
    extra_files = {"design.yaml": result.design_yaml_dict()}

    def writers(st):
        st.remove("pareto.csv")
        st.remove("pareto.png")

    if front:
        from mst_cli.design.pareto import pareto_csv, plot_pareto

        extra["pareto"] = {
            "designs": len(front),
            "requested": pareto_count,
            "files": ["pareto.csv"]
            + (["pareto.png"] if plot else [])
            + ([f"pareto/design-{k + 1:02d}.yaml" for k in range(len(front))] if pareto_designs else []),
        }
        if pareto_designs:
            extra_files.update(
                {f"pareto/design-{k + 1:02d}.yaml": p.result.design_yaml_dict() for k, p in enumerate(front)}
            )

        def writers(st):
            st.write_text("pareto.csv", pareto_csv(front))
            if plot:
                plot_pareto(front, st.path("pareto.png"), title=f"{name}: designs that meet every target")
            else:
                st.remove("pareto.png")

    return write_simulation(
        result.document,
        result.geometry,
        result.response,
        out,
        extra_files=extra_files,
        extra_report=extra,
        more=writers,
        plot=plot,
    )


def _print_summary(
    result, front, pareto_count: int | None, pareto_designs: bool, out: Path, plot: bool, seconds: float
) -> None:
    click.echo(result.table())
    if front:
        from mst_cli.design.pareto import front_table

        click.echo(front_table(front))
    elif pareto_count is not None:
        click.echo("Pareto front: not mapped (the targets are not met)")
    files = (
        "design.yaml, report.json, response.csv"
        + (", response.png" if plot else "")
        + (", pareto.csv" + (", pareto.png" if plot else "") if front else "")
        + (f", pareto/ ({len(front)} designs)" if front and pareto_designs else "")
    )
    click.echo(f"wrote {out}/{files} ({seconds:.2f} s)")
