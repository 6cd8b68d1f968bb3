"""The dear rungs' law memo and its side-by-side solves (mst_cli/model/mechanics/law_cache.py)."""

import numpy as np
import pytest

from mst_cli.model.cell import HexCell
from mst_cli.model.material import Material
from mst_cli.model.mechanics import continuum
from mst_cli.model.mechanics.law_cache import LawCache
from mst_cli.parallel import can_fork

needs_fork = pytest.mark.skipif(not can_fork(), reason="side-by-side solves fork, on Linux only")


def _square(cell, material):
    if cell < 0:
        raise ValueError(f"no law for cell {cell}")
    return (cell * cell, material)


@needs_fork
def test_continuum_laws_solved_side_by_side_equal_those_solved_in_turn(monkeypatch):
    """Three cells of a stack: the laws two workers return are bit for bit the ones this
    process solves, and each is then served from the memo."""
    cells = [HexCell(theta_deg=th, t_mm=0.45, h_mm=2.4) for th in (14.0, 22.0, 30.0)]
    material = Material()
    monkeypatch.setenv("MST_WORKERS", "2")
    parallel = LawCache(continuum.continuum_layer.__wrapped__, 8)
    parallel.solve_many((c, material) for c in cells)
    assert parallel.solved_in_workers == 3 and parallel.cache_info().misses == 3
    serial = LawCache(continuum.continuum_layer.__wrapped__, 8)
    for c in cells:
        a, b = parallel(c, material), serial(c, material)
        assert a.lock_force_N == b.lock_force_N and a.k_N_per_mm == b.k_N_per_mm
        assert np.array_equal(a.knots_N, b.knots_N)
        assert np.array_equal(a.displacement_mm(a.knots_N), b.displacement_mm(b.knots_N))
    assert parallel.cache_info().hits == 3 and serial.cache_info().misses == 3


@needs_fork
def test_a_worker_failure_is_raised_as_in_turn(monkeypatch):
    monkeypatch.setenv("MST_WORKERS", "2")
    cache = LawCache(_square, 8)
    with pytest.raises(ValueError, match="no law for cell -2"):
        cache.solve_many([(3, "m"), (-2, "m"), (5, "m")])


def test_one_worker_leaves_the_solves_to_the_requests(monkeypatch):
    monkeypatch.setenv("MST_WORKERS", "1")
    cache = LawCache(_square, 8)
    cache.solve_many([(3, "m"), (4, "m")])
    assert cache.cache_info().misses == 0
    assert cache(3, "m") == (9, "m") and cache(3, "m") == (9, "m")
    assert cache.cache_info()[:2] == (1, 1)


def test_the_memo_keeps_the_newest(monkeypatch):
    cache = LawCache(_square, 2)
    for cell in (1, 2, 1, 3):  # 2 is the least recently used when 3 arrives
        cache(cell, "m")
    assert cache.cache_info().currsize == 2 and cache.cache_info().misses == 3
    cache(1, "m")
    assert cache.cache_info().hits == 2
    cache.cache_clear()
    assert cache.cache_info() == (0, 0, 2, 0)
