"""Shared test setup: the repository's paths, and no picture window on a headless machine."""

from __future__ import annotations

import os
import tempfile
from pathlib import Path

import pytest

os.environ.setdefault("MPLBACKEND", "Agg")  # before any test imports matplotlib
os.environ.setdefault("MST_CACHE_DIR", tempfile.mkdtemp(prefix="mst-test-cache-"))  # module fixtures too

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
