"""The ``mst`` command group. Thin: it parses options, calls :mod:`mst_cli.api`, prints.

Every command lives in its own module of this package and imports only
:mod:`mst_cli.cli.common` from here; this module imports the commands (one direction), and
only the one being run: a command module is loaded when click asks for it, so ``mst simulate``
does not pay for the imports of ``calibrate``, ``slice`` or ``export`` (about 20 ms of a
0.3 s run; ``benchmarks/bench_simulate.py``). Heavy libraries (build123d, scikit-fem,
matplotlib) are imported inside the commands that need them.
"""

from __future__ import annotations

import click

from mst_cli.cli.common import MstGroup

# the order of `mst --help` (the README's: the workflow)
COMMANDS = ("simulate", "design", "export", "check", "slice", "calibrate", "read", "bench")


def load_command(name: str) -> click.Command | None:
    """The click command ``name``, its module imported now (None for an unknown name).

    Plain import statements, not importlib strings, so tests/test_architecture.py sees them."""
    if name == "simulate":
        from mst_cli.cli.simulate import simulate  # deferred: only the command run is loaded

        return simulate
    if name == "design":
        from mst_cli.cli.design import design  # deferred: only the command run is loaded

        return design
    if name == "export":
        from mst_cli.cli.export import export  # deferred: only the command run is loaded

        return export
    if name == "check":
        from mst_cli.cli.export import check  # deferred: only the command run is loaded

        return check
    if name == "bench":
        from mst_cli.cli.bench import bench  # deferred: only the command run is loaded

        return bench
    if name == "slice":
        from mst_cli.cli.slice import slice_  # deferred: only the command run is loaded

        return slice_
    if name == "calibrate":
        from mst_cli.cli.calibrate import calibrate  # deferred: only the command run is loaded

        return calibrate
    if name == "read":
        from mst_cli.cli.read import read  # deferred: only the command run is loaded

        return read
    return None


class LazyMstGroup(MstGroup):
    """:class:`MstGroup` whose commands are imported on first use."""

    def list_commands(self, ctx: click.Context) -> list[str]:
        return list(COMMANDS)

    def get_command(self, ctx: click.Context, cmd_name: str) -> click.Command | None:
        return load_command(cmd_name)


@click.group(cls=LazyMstGroup, context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(package_name="mst", prog_name="mst")  # read from the metadata when asked
def main() -> None:
    """Design multi-sensitivity soft tactile (MST) sensors.

    A stack of collapsible 3D-printed TPU layers, a magnet above it and an MLX90393
    magnetometer below: each layer locks at its own force, so one sensor has several
    sensitivities over several force bands. Units: mm, N, MPa, degrees, mT.

    \b
    mst simulate DESIGN.yaml   forward model: curves, S_i, R_i, field, chip settings
    mst design SPEC.yaml       inverse design from target S_i and R_i to theta, t, h
    mst export DESIGN.yaml     printable STL / 3MF / STEP of the stacked assembly
    mst check PATH             geometry checks of what export wrote
    mst slice PATH             slice the export with PrusaSlicer and judge the print
    mst calibrate DESIGN CSV   fit the print parameters to a load test
    mst read MODEL CSV         MLX90393 readings (or --serial PORT) to forces
    mst bench                  measured speed/accuracy table of the models

    Exit codes: 0 success, 1 targets not met or checks failed, 2 invalid input.
    """
