"""The ``mst`` command group. Thin: it parses options, calls the library, writes files.

Every command lives in its own module of this package and imports only
:mod:`mst_cli.cli.common` from here; this module imports the commands (one direction).
Heavy libraries (build123d, scikit-fem, matplotlib) are imported inside the commands that
need them.
"""

from __future__ import annotations

import click

from mst_cli import __version__
from mst_cli.cli.bench import bench
from mst_cli.cli.calibrate import calibrate, read
from mst_cli.cli.common import MstGroup
from mst_cli.cli.design import design
from mst_cli.cli.export import check, export
from mst_cli.cli.simulate import simulate
from mst_cli.cli.slice import slice_


@click.group(cls=MstGroup, context_settings={"help_option_names": ["-h", "--help"]})
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


for command in (simulate, design, export, check, bench, slice_, calibrate, read):
    main.add_command(command)
