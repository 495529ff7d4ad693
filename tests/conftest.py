"""Shared test setup.

- Makes the tamias2d of this checkout importable when pytest is started from
  elsewhere than the repository root.
- ``rng``: a seeded random.Random, so randomized tests are reproducible.
- Prints the table of the pymunk test-suite run (test_pymunk_suite.py) at the
  end of the session.
"""
import importlib.util
import os
import random
import sys

import pytest

_ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
if importlib.util.find_spec("tamias2d") is None:
    sys.path.insert(0, os.path.join(_ROOT, "src"))


@pytest.fixture
def rng():
    """A random.Random with a fixed seed."""
    return random.Random(20240607)


def pytest_terminal_summary(terminalreporter, exitstatus, config):
    compat = sys.modules.get("pymunk_compat")
    if compat is None or not compat.SUMMARY:
        return
    terminalreporter.section("pymunk's unit tests on tamias2d")
    for line in compat.format_summary(compat.SUMMARY).splitlines():
        terminalreporter.write_line(line)
