"""The suite's plumbing: each test module starts with the package's caches empty, and memory
figures of a run on request (results/bench_test_suite.md).

The package keeps the NLPs, solvers and checks of the specs used last (pdm_design/lru.py): a few
MB each, a few hundred MB for the long stairs rows of the yield-target tests. Kept from one
module to the next they only add up (1.9 GB by the end of the suite, 0.7 GB of it held by
modules whose specs no later module reads); emptied after each module, and the freed heap handed
back to the system (glibc's malloc_trim), each module's memory is its own.

PDM_TEST_MEMLOG=FILE appends, after each test module, one line per module to FILE: the worker,
the module, the resident memory (MB) after it and the peak so far; and at the end of the run the
worker's peak resident memory (ru_maxrss). Each pytest-xdist worker writes its own lines.
"""

from __future__ import annotations

import ctypes
import gc
import os
import resource
import sys

import pytest

MEMLOG = os.environ.get("PDM_TEST_MEMLOG")

# The modules that build the largest NLPs (several hundred MB each while they run): each of
# their tests empties the caches when it ends, so two tests' NLPs are never held at once.
LARGE_NLPS = frozenset({
    "test_allocation_built.py",
    "test_compass_gait_formulation.py",
    "test_rimless_wheel_rough.py",
    "test_yield_target_monte_carlo.py",
    "test_yield_target_optimize.py",
    "test_yield_target_stairs.py",
})
# Under pytest-xdist (`--dist loadgroup`, pyproject.toml) these and the other modules whose
# peak is 150 MB or more above a worker's run one after another on one worker, so the two
# workers' peaks never come from two of them at once; every other module is a group of its own
# (its module fixtures built once, on one worker). results/bench_test_suite.md has the figures.
ONE_WORKER = LARGE_NLPS | {"test_max_yield.py", "test_max_yield_stairs.py", "test_newcomer.py"}


@pytest.hookimpl(tryfirst=True)  # before pytest-xdist reads the groups
def pytest_collection_modifyitems(config, items):
    for item in items:
        if item.get_closest_marker("xdist_group") is None:
            name = item.path.name
            item.add_marker(pytest.mark.xdist_group("one_worker" if name in ONE_WORKER
                                                    else name))


def _worker(config) -> str:
    return os.environ.get("PYTEST_XDIST_WORKER", "main")


def _rss_mb() -> float:
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE") / 2**20


def _peak_mb() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024


def _log(line: str) -> None:
    with open(MEMLOG, "a", encoding="utf-8") as f:
        f.write(line + "\n")


def _empty_caches() -> None:
    """Empty every bounded cache of the package (pdm_design.lru.Bounded, wherever held) and
    the yield checks kept; close open figures; return the freed heap to the system."""
    from pdm_design.lru import Bounded

    for name, module in list(sys.modules.items()):
        if name.startswith("pdm_design") and module is not None:
            for value in list(vars(module).values()):
                if isinstance(value, Bounded):
                    value.clear()
    checks = sys.modules.get("pdm_design.solve.yield_check")
    if checks is not None:
        checks._CACHE.clear()
    if "matplotlib.pyplot" in sys.modules:
        sys.modules["matplotlib.pyplot"].close("all")
    gc.collect()
    _trim()


def _trim() -> None:
    try:
        ctypes.CDLL("libc.so.6").malloc_trim(0)
    except (OSError, AttributeError):  # not glibc
        pass


@pytest.fixture(autouse=True)
def _large_nlps_one_at_a_time(request):
    """In the modules of LARGE_NLPS, each test's NLPs go when it ends: the next test builds
    its own rather than holding two sets of them at once."""
    yield
    if request.node.path.name in LARGE_NLPS:
        _empty_caches()


@pytest.fixture(scope="module", autouse=True)
def _module_memory(request):
    yield
    _empty_caches()
    if MEMLOG:
        figures = len(sys.modules["matplotlib.pyplot"].get_fignums()) \
            if "matplotlib.pyplot" in sys.modules else 0
        _log(f"module {_worker(request.config)} {request.node.nodeid} "
             f"rss={_rss_mb():.0f} peak={_peak_mb():.0f} figures={figures}")


def pytest_sessionfinish(session):
    if MEMLOG:
        _log(f"peak {_worker(session.config)} {_peak_mb():.0f}")


@pytest.fixture(scope="session")
def rocking_skips(tmp_path_factory):
    """results/rocking_row.toml with `[verification] allow_skips = true` (as an engine without
    the row's skip rule counts): (the spec, its design, its tolerances for 8 stages)."""
    from pathlib import Path

    from pdm_design.commands.yield_ import sized_tolerances
    from pdm_design.spec.loader import load_spec

    text = (Path(__file__).resolve().parents[1] / "results" / "rocking_row.toml").read_text()
    path = tmp_path_factory.mktemp("rocking") / "rocking_skips.toml"
    path.write_text(text.replace("[verification]", "[verification]\nallow_skips = true", 1))
    spec = load_spec(path)
    design = spec.design_at()
    return spec, design, sized_tolerances(spec, path, design, 8)
