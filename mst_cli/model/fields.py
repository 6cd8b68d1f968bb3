"""Declaring an input field once: a dataclass field with the metadata a design file needs."""

from __future__ import annotations

from dataclasses import MISSING, field


def spec(default=MISSING, *, meaning: str, unit: str = "", lo=None, hi=None, lo_open=False, hi_open=False,
         choices=(), nullable=False, kind=None, omit_default=False, default_factory=MISSING):
    """A dataclass field that design files may set: its default, plus metadata saying what a file
    may give (unit, bounds or choices, whether null is allowed, a one-line meaning).

    This is the one declaration of an input field: :mod:`mst_cli.io.schema` derives the
    validation rule, the default, the serialisation and the table in docs/file-format.md from it.
    It lives in model/, not io/, because the model's own dataclasses carry the defaults and
    model/ may not import io/. ``kind`` is needed only where the annotation does not say it
    ("pair", "bounds", "weights"); ``omit_default`` leaves the key out of a written file while it
    holds its default.
    """
    meta = {"meaning": meaning, "unit": unit, "lo": lo, "hi": hi, "lo_open": lo_open, "hi_open": hi_open,
            "choices": tuple(choices), "nullable": nullable, "kind": kind, "omit_default": omit_default}
    return field(default=default, default_factory=default_factory, metadata=meta)
