"""The type of the kernels' numeric parameters.

The array kernels (``model.cell``, ``model.mechanics.spring`` ...) take a number or a numpy
array of any shape and broadcast: ``Floats`` says so to the type checker, where numpy's
``ArrayLike`` (lists and nested sequences too) would not support arithmetic.
"""

from __future__ import annotations

from typing import TypeAlias

import numpy as np

Floats: TypeAlias = np.ndarray | float
