"""Shared fixtures: a private render cache per test session, seeded generators."""

from __future__ import annotations

import os
import sys
from pathlib import Path

import numpy as np
import pytest

# tests import their shared reference routes from tests/helpers.py
sys.path.insert(0, str(Path(__file__).resolve().parent))

# every test runs compiled kernels, compiled in the test's own process (and its children's):
# tests/common/test_background.py asks for the default, a kernel run as Python while a
# background process compiles it, where it tests that
os.environ["TOOLKIT_COMPILE"] = "wait"


@pytest.fixture(autouse=True, scope="session")
def _private_cache(tmp_path_factory: pytest.TempPathFactory):
    """Render into a fresh cache folder so every session exercises xacro for real."""
    mp = pytest.MonkeyPatch()
    mp.setenv("TOOLKIT_CACHE_DIR", str(tmp_path_factory.mktemp("render-cache")))
    yield
    mp.undo()


@pytest.fixture
def rng() -> np.random.Generator:
    return np.random.default_rng(12345)


@pytest.fixture(autouse=True)
def _close_figures():
    """Every figure a test opens is closed after it (pyplot keeps them otherwise)."""
    yield
    pyplot = sys.modules.get("matplotlib.pyplot")
    if pyplot is not None:
        pyplot.close("all")


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    """The notebooks (executed by nbmake) are slow: each starts a kernel and compiles."""
    for item in items:
        if item.path.suffix == ".ipynb":
            item.add_marker(pytest.mark.slow)
