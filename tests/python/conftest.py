"""Shared settings of the Python package's tests: the build folder's package and binary."""
import os
import sys

import pytest

REPO = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
BUILD = os.environ.get("GRANULAR_BUILD", os.path.join(REPO, "build"))
sys.path.insert(0, os.path.join(BUILD, "python"))


@pytest.fixture(scope="session")
def granular():
    import granular as g
    g.initialize(int(os.environ.get("GRANULAR_THREADS", "2")))
    return g


@pytest.fixture(scope="session")
def binary():
    return os.path.join(BUILD, "bin", "granular")
