"""Inverse design: from target sensitivities and force ranges to theta, t, h per layer.

The public entry points; the parts live in their own modules: :mod:`.problem` (the vectorised
forward problem and the preference), :mod:`.seed` (the layer-by-layer start), :mod:`.phase`
(the one nlopt runner), :mod:`.solver` (Gauss-Newton match, nlopt preference polish,
multi-start fallback), :mod:`.batching` (many weightings' polishes, their kernel calls pooled),
:mod:`.document` (a spec in, a verified design out), :mod:`.refine` (a dearer rung's local
match), :mod:`.pareto` (the trade-off front), :mod:`.explain` (why a spec cannot be met).
"""

from mst_cli.design.document import design_document
from mst_cli.design.result import DesignResult
from mst_cli.design.verify import verify_design

__all__ = ["DesignResult", "design_document", "verify_design"]
