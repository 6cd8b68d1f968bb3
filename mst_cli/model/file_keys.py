"""Declaring an input field once: a dataclass field with the metadata a design file needs."""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import MISSING, field
from typing import Any

# The random seed's range, shared by design.seed in a spec, 'mst design --seed' and 'mst bench
# --seed' (one owner: what one accepts, the others accept).
SEED_RANGE = (0, 2**32 - 1)


def spec(
    default: Any = MISSING,
    *,
    meaning: str,
    unit: str = "",
    lo: float | None = None,
    hi: float | None = None,
    lo_open: bool = False,
    hi_open: bool = False,
    choices: Iterable[Any] = (),
    nullable: bool = False,
    kind: str | None = None,
    omit_default: bool = False,
    default_factory: Any = MISSING,
) -> Any:
    """A dataclass field that design files may set: its default, plus metadata saying what a file
    may give (unit, bounds or choices, whether null is allowed, a one-line meaning).

    This is the one declaration of an input field: :mod:`mst_cli.sensor.document` derives the
    validation rule, the default, the serialisation and the table in docs/file-format.md from it.
    It lives in model/, not io/, because the model's own dataclasses carry the defaults and
    model/ may not import io/. ``kind`` is needed only where the annotation does not say it
    ("pair", "bounds", "weights"); ``omit_default`` leaves the key out of a written file while it
    holds its default.
    """
    meta = {
        "meaning": meaning,
        "unit": unit,
        "lo": lo,
        "hi": hi,
        "lo_open": lo_open,
        "hi_open": hi_open,
        "choices": tuple(choices),
        "nullable": nullable,
        "kind": kind,
        "omit_default": omit_default,
    }
    return field(default=default, default_factory=default_factory, metadata=meta)
