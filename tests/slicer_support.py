"""Whether the slicer tests can run: PrusaSlicer's command line on PATH. Outside CI they skip
saying why; in CI (.ci/run installs it) a missing slicer is a failure."""

import os
import shutil

import pytest

HAVE_SLICER = shutil.which("prusa-slicer") is not None
IN_CI = os.environ.get("CI") == "true"


def need_slicer():
    if HAVE_SLICER:
        return
    if IN_CI:
        pytest.fail("prusa-slicer is not installed in CI (apt-get install prusa-slicer)")
    pytest.skip("prusa-slicer is not installed (apt-get install prusa-slicer); CI runs these tests")
