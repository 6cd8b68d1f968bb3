"""Shared test setup: the repository's paths, and no picture window on a headless machine."""

from __future__ import annotations

import os
import tempfile
from pathlib import Path

import pytest

from mst_cli.sensor import rung_store

os.environ.setdefault("MPLBACKEND", "Agg")  # before any test imports matplotlib
os.environ.setdefault("MST_CACHE_DIR", tempfile.mkdtemp(prefix="mst-test-cache-"))  # module fixtures too

# The whole-part rung's solves are pure functions of what they are keyed by: one folder for the
# session's tests (each worker's), so a part solved by one test is not solved again by the next
# (mst_cli.sensor.rung_store; the tables above stay each test's own).
rung_store.install(Path(tempfile.mkdtemp(prefix="mst-test-rung-")))

ROOT = Path(__file__).resolve().parents[1]
CONFIGS = ROOT / "configs"


@pytest.fixture
def configs_dir() -> Path:
    """The bundled example files (configs/)."""
    return CONFIGS


@pytest.fixture(autouse=True)
def own_table_cache(tmp_path_factory, monkeypatch):
    """Each test keeps the tables it builds in a cache folder of its own (mst_cli.io.cache):
    no test finds another's, and none writes to the user's home."""
    monkeypatch.setenv("MST_CACHE_DIR", str(tmp_path_factory.mktemp("cache")))
