"""Choosing a mechanics rung from a requested accuracy (docs/design.md section 4).

One place for the rule both ``mst simulate`` and ``mst design`` follow: an explicit command-line
flag wins; else a file's ``model.accuracy_rel`` picks the cheapest rung whose MEASURED median
errors against the continuum reference, in layer stiffness and in lock force, both meet it
(:func:`cheapest_model_for`, numbers stored in mst_cli/model/data/ladder_errors.json and
written by ``mst bench`` / benchmarks/bench_ladder.py);
else the file's ``model.mechanics``.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np

LADDER = ("spring-textbook", "spring", "frame", "continuum")  # cheapest first; continuum is the reference
# what a user can pick: "spring-textbook" is L0 without its fitted correction, a bench row only
USER_LADDER = ("spring", "frame", "continuum")
ERRORS_FILE = Path(__file__).resolve().parent / "data" / "ladder_errors.json"


def load_ladder_errors(path: Path = ERRORS_FILE) -> dict:
    """The measured median errors (stiffness, lock force, lock displacement) and times per rung
    stored with the package."""
    return json.loads(Path(path).read_text())


def rung_errors(model: str, errors: dict) -> dict:
    """Measured median |error| of one rung against L2: {"k": .., "lock_force": ..} (0 for L2).

    These are the two numbers a design's targets rest on: the sensitivity S follows the layer
    stiffness k, the force range R is the lock force. A rung without a stored lock-force
    error (a bench before it was measured) counts as unmeasured there, i.e. infinitely wrong.
    """
    if model == LADDER[-1]:
        return {"k": 0.0, "lock_force": 0.0}
    entry = errors["models"][model]
    return {"k": float(entry["median_abs_err_k"]), "lock_force": float(entry.get("median_abs_err_lock_force", np.inf))}


def cheapest_model_for(accuracy_rel: float, errors: dict | None = None) -> tuple[str, dict]:
    """The cheapest mechanics rung whose MEASURED median |error| against L2, in stiffness AND
    in lock force, is at most ``accuracy_rel`` (e.g. 0.05 for 5 %), and those errors.

    A rung is only as accurate as the worse of the two: a correct k with a lock force 50 %
    off would put every force range of a design off by that much. The reference rung
    ``continuum`` has error 0 by definition, so it is returned when no cheaper rung
    qualifies. Raises ValueError for accuracy_rel <= 0 or not finite.
    """
    if not (np.isfinite(accuracy_rel) and accuracy_rel > 0):
        raise ValueError(f"accuracy_rel must be a positive number, got {accuracy_rel!r}")
    errors = load_ladder_errors() if errors is None else errors
    for model in USER_LADDER:
        err = rung_errors(model, errors)
        if max(err.values()) <= accuracy_rel:
            return model, err
    return LADDER[-1], rung_errors(LADDER[-1], errors)


@dataclass(frozen=True)
class MechanicsChoice:
    """The rung to use and, when it came from accuracy_rel, the line that says why."""

    mechanics: str
    source: str  # "flag", "accuracy_rel" or "file"
    measured_err_k_rel: float | None = None
    measured_err_lock_force_rel: float | None = None
    requested_rel: float | None = None

    def message(self) -> str | None:
        """One line for the user, or None when nothing was picked on their behalf."""
        if self.source != "accuracy_rel":
            return None
        err_k, err_R, asked = self.measured_err_k_rel, self.measured_err_lock_force_rel, self.requested_rel
        # a pick by accuracy_rel always records the measured errors and the request
        assert err_k is not None and err_R is not None and asked is not None
        return (
            f"mechanics: {self.mechanics} (measured median error against continuum: stiffness "
            f"{100 * err_k:.3g} %, lock force {100 * err_R:.3g} %; requested <= {100 * asked:.3g} %)"
        )


def choose_mechanics(
    explicit: str | None, accuracy_rel: float | None, file_mechanics: str, errors: dict | None = None
) -> MechanicsChoice:
    """The mechanics rung to run.

    Parameters
    ----------
    explicit : str or None
        The command-line choice (--mechanics / --refine); wins when given.
    accuracy_rel : float or None
        The file's model.accuracy_rel (relative accuracy of stiffness and lock force, 0 < a < 1).
    file_mechanics : str
        The file's model.mechanics, used when neither of the above is given.
    errors : dict, optional
        Ladder errors in the format of mst_cli/model/data/ladder_errors.json [default: the stored ones].
    """
    if explicit is not None:
        return MechanicsChoice(explicit, "flag")
    if accuracy_rel is None:
        return MechanicsChoice(file_mechanics, "file")
    model, err = cheapest_model_for(float(accuracy_rel), errors)
    return MechanicsChoice(model, "accuracy_rel", err["k"], err["lock_force"], float(accuracy_rel))
