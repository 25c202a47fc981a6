"""Shared fixtures: fixed seeds, and Mitsuba 3 in the best variant that
works here (skipping cleanly when it cannot be imported)."""

from __future__ import annotations

import numpy as np
import pytest

import mcsample as mcs
from mcsample import mitsuba as mcs_mitsuba


@pytest.fixture
def rng() -> np.random.Generator:
    return np.random.default_rng(12345)


@pytest.fixture
def sigint_interrupts():
    """Python's own SIGINT handler (KeyboardInterrupt) for the test, also
    where the suite runs with SIGINT ignored (a shell's background job)."""
    import signal

    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    yield
    signal.signal(signal.SIGINT, previous)


@pytest.fixture(scope="session")
def mi():
    """The mitsuba module with a variant set: llvm_ad_rgb when a usable
    libLLVM exists, else scalar_rgb."""
    if not mcs_mitsuba.available():
        pytest.skip("Mitsuba 3 is not installed (pip install 'mcsample[mitsuba]')")
    return mcs_mitsuba.load()


@pytest.fixture(autouse=True)
def _restore_threads():
    n = mcs.get_num_threads()
    yield
    mcs.set_num_threads(n)
