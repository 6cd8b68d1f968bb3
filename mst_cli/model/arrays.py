"""The type of the kernels' numeric parameters, and the one way they stack terms.

The array kernels (``model.cell``, ``model.mechanics.spring`` ...) take a number or a numpy
array of any shape and broadcast: ``Floats`` says so to the type checker, where numpy's
``ArrayLike`` (lists and nested sequences too) would not support arithmetic.
"""

from __future__ import annotations

from typing import TypeAlias

import numpy as np

Floats: TypeAlias = np.ndarray | float


def stacked_terms(*terms: np.ndarray | float) -> np.ndarray:
    """The terms (arrays and numbers, broadcast) as columns of a new last axis, float:
    ``np.stack(np.broadcast_arrays(*terms), axis=-1)``, the same array (C order, the same bits
    into a matmul or an einsum), filled in place: half the time on the design loop's small
    batches, where the fits' design matrices are built a few hundred times a run."""
    out = np.empty(np.broadcast(*terms).shape + (len(terms),))
    for j, term in enumerate(terms):
        out[..., j] = term
    return out
