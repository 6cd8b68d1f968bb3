"""The one error every layer raises for input a user can fix.

``InputError(field, value, allowed)`` names the offending field as a dotted path
(``layers[1].t_mm``), the value and what is allowed; the command line prints it as one line
and exits with code 2 (docs/design.md section 5). It lives below every other module so that
geometry, CAD, checks and design can raise it without depending on the file parser.
"""

from __future__ import annotations

from typing import Any

MAX_SHOWN_CHARS = 120  # a value longer than this is shortened in the one-line message


def _shown(value: Any) -> str:
    text = repr(value)
    return text if len(text) <= MAX_SHOWN_CHARS else f"{text[: MAX_SHOWN_CHARS - 40]}... ({len(text)} chars)"


class InputError(ValueError):
    """Invalid input: ``field`` is a dotted path such as ``layers[1].t_mm``."""

    def __init__(self, field: str, value: Any, allowed: str):
        self.field, self.value, self.allowed = field, value, allowed
        field = str(field) if len(str(field)) <= MAX_SHOWN_CHARS else _shown(str(field))
        super().__init__(f"{field} = {_shown(value)}: {allowed}")


class CalibrationFailed(RuntimeError):
    """The fit itself failed (not the input's form): the message says why."""
