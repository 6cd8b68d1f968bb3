"""Choosing a mechanics rung from a requested accuracy (DESIGN.md section 4).

One place for the rule both ``mst simulate`` and ``mst design`` follow: an explicit command-line
flag wins; else a file's ``model.accuracy_rel`` picks the cheapest rung whose MEASURED median
stiffness error against the continuum reference meets it (:func:`mst_cli.bench.cheapest_model_for`,
numbers stored in mst_cli/data/ladder_errors.json); else the file's ``model.mechanics``.
"""

from __future__ import annotations

from dataclasses import dataclass

USER_MODELS = ("spring", "frame", "continuum")


@dataclass(frozen=True)
class MechanicsChoice:
    """The rung to use and, when it came from accuracy_rel, the line that says why."""

    mechanics: str
    source: str                     # "flag", "accuracy_rel" or "file"
    measured_err_rel: float | None = None
    requested_rel: float | None = None

    def message(self) -> str | None:
        """One line for the user, or None when nothing was picked on their behalf."""
        if self.source != "accuracy_rel":
            return None
        return (f"mechanics: {self.mechanics} (measured median stiffness error "
                f"{100 * self.measured_err_rel:.3g} % <= requested {100 * self.requested_rel:.3g} %)")


def choose_mechanics(explicit: str | None, accuracy_rel: float | None, file_mechanics: str,
                     errors: dict | None = None) -> MechanicsChoice:
    """The mechanics rung to run.

    Parameters
    ----------
    explicit : str or None
        The command-line choice (--mechanics / --refine); wins when given.
    accuracy_rel : float or None
        The file's model.accuracy_rel (relative stiffness accuracy, 0 < a < 1).
    file_mechanics : str
        The file's model.mechanics, used when neither of the above is given.
    errors : dict, optional
        Ladder errors in the format of mst_cli/data/ladder_errors.json [default: the stored ones].
    """
    if explicit is not None:
        return MechanicsChoice(explicit, "flag")
    if accuracy_rel is None:
        return MechanicsChoice(file_mechanics, "file")
    from .bench import cheapest_model_for
    model, err = cheapest_model_for(float(accuracy_rel), errors)
    # the bench may list L0 variants (textbook / corrected): all are the user's "spring" rung
    if model not in USER_MODELS and model.startswith("spring"):
        model = "spring"
    return MechanicsChoice(model, "accuracy_rel", float(err), float(accuracy_rel))
