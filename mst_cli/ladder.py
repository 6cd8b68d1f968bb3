"""Choosing a mechanics rung from a requested accuracy (DESIGN.md section 4).

One place for the rule both ``mst simulate`` and ``mst design`` follow: an explicit command-line
flag wins; else a file's ``model.accuracy_rel`` picks the cheapest rung whose MEASURED median
errors against the continuum reference, in layer stiffness and in lock force, both meet it
(:func:`mst_cli.bench.cheapest_model_for`, numbers stored in mst_cli/data/ladder_errors.json);
else the file's ``model.mechanics``.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class MechanicsChoice:
    """The rung to use and, when it came from accuracy_rel, the line that says why."""

    mechanics: str
    source: str                     # "flag", "accuracy_rel" or "file"
    measured_err_k_rel: float | None = None
    measured_err_lock_force_rel: float | None = None
    requested_rel: float | None = None

    def message(self) -> str | None:
        """One line for the user, or None when nothing was picked on their behalf."""
        if self.source != "accuracy_rel":
            return None
        return (f"mechanics: {self.mechanics} (measured median error against continuum: stiffness "
                f"{100 * self.measured_err_k_rel:.3g} %, lock force {100 * self.measured_err_lock_force_rel:.3g} %; "
                f"requested <= {100 * self.requested_rel:.3g} %)")


def choose_mechanics(explicit: str | None, accuracy_rel: float | None, file_mechanics: str,
                     errors: dict | None = None) -> MechanicsChoice:
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
        Ladder errors in the format of mst_cli/data/ladder_errors.json [default: the stored ones].
    """
    if explicit is not None:
        return MechanicsChoice(explicit, "flag")
    if accuracy_rel is None:
        return MechanicsChoice(file_mechanics, "file")
    from .bench import cheapest_model_for
    model, err = cheapest_model_for(float(accuracy_rel), errors)
    return MechanicsChoice(model, "accuracy_rel", err["k"], err["lock_force"], float(accuracy_rel))
