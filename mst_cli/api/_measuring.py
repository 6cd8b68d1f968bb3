"""The model ladder measured: ``mst bench``.

Part of the api's one door, :mod:`mst_cli.api`."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

from mst_cli.api._common import _check_out
from mst_cli.errors import InputError
from mst_cli.io.files import is_machine_fault as is_machine_fault
from mst_cli.io.files import os_error_text as os_error_text
from mst_cli.io.outputs import Interrupted as Interrupted
from mst_cli.model.file_keys import SEED_RANGE as SEED_RANGE

if TYPE_CHECKING:
    from mst_cli.bench.ladder_bench import BenchResult


def bench(
    *, samples: int = 24, seed: int = 0, quick: bool = False, out: str | Path | None = None, plot: bool = True
) -> BenchResult:
    """Measure the model ladder against its references (``mst bench``).

    Parameters
    ----------
    samples : int
        Seeded valid designs across the bounds (1 to 500).
    seed : int
        Seed of the sample.
    quick : bool
        Skip the continuum mesh-convergence study and the tilt rung's check against L2.
    out : str or Path, optional
        Folder for bench.json, bench.md and (``plot``) bench.png, written atomically
        [default: nothing written].

    Returns
    -------
    BenchResult
        bench.json's dict: per rung (spring, frame) the stiffness and lock-force errors against
        continuum FE and the time per layer, per field model the error against magpylib, the
        mesh convergence and the tilt rung's error; ``.markdown()`` is bench.md.

    Raises
    ------
    InputError
        A bad sample count or output folder.

    Examples
    --------
    >>> print(mst.bench(samples=4, quick=True).markdown())  # doctest: +SKIP
    """
    from mst_cli.bench.ladder_bench import BenchResult, run_bench  # deferred: scipy and scikit-fem, 160 ms measured

    if not 1 <= samples <= 500:
        raise InputError("--samples", samples, "must be an integer from 1 to 500")
    _check_out(out)
    result = BenchResult(run_bench(samples=samples, seed=seed, quick=quick))
    if out is not None:
        result.write(Path(out), plot)
    return result
