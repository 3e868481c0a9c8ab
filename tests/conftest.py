"""Shared test fixtures.

Real data lives in ``../shared/data`` beside the checkout (or where
``MAP2MAP_SHARED_DATA`` points); tests that need it skip cleanly when it is absent.
"""

from __future__ import annotations

import os
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
SHARED_DATA = Path(os.environ.get("MAP2MAP_SHARED_DATA", REPO.parent / "shared" / "data"))


@pytest.fixture
def shared_data() -> Path:
    """Path of ``../shared/data``; skips the test when it is absent."""
    if not SHARED_DATA.is_dir():
        pytest.skip(f"shared data not found at {SHARED_DATA}")
    return SHARED_DATA


@pytest.fixture(scope="session")
def chromium() -> str:
    """Path of headless Chromium (tests/browser.py); skips when absent, unless CI
    (``MAP2MAP_REQUIRE_BROWSER=1``, set by ``.ci/run``) requires it: then it fails."""
    from browser import find_chromium  # tests/ is on sys.path (pytest's rootdir import)

    path = find_chromium()
    if path is None:
        message = "chromium not found (apt-get install chromium)"
        if os.environ.get("MAP2MAP_REQUIRE_BROWSER") == "1":
            pytest.fail(f"{message}; MAP2MAP_REQUIRE_BROWSER=1 requires it")
        pytest.skip(message)
    return path


@pytest.fixture
def one_torch_thread():
    """One intra-op torch thread for the test: tiny networks on a shared machine run
    faster without them (torch imported here, so the conftest stays light)."""
    import torch

    n = torch.get_num_threads()
    torch.set_num_threads(1)
    yield
    torch.set_num_threads(n)
