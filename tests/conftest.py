"""Shared test setup: the repository's paths, and no picture window on a headless machine."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

os.environ.setdefault("MPLBACKEND", "Agg")  # before any test imports matplotlib

ROOT = Path(__file__).resolve().parents[1]
CONFIGS = ROOT / "configs"


@pytest.fixture
def configs_dir() -> Path:
    """The bundled example files (configs/)."""
    return CONFIGS
