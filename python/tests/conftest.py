"""Shared fixtures of capdyn's Python tests (run by `make python-test` /
`make test`, which set CAPDYN_ROOT, CAPDYN_BIN, CAPDYN_BUILD)."""
import os
import subprocess

import pytest

ROOT = os.environ.get("CAPDYN_ROOT") or os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
BUILD = os.environ.get("CAPDYN_BUILD") or os.path.join(ROOT, "build")
BIN = os.environ.get("CAPDYN_BIN") or os.path.join(BUILD, "capdyn")


def scenario(name):
    return os.path.join(ROOT, "scenarios", name)


@pytest.fixture(scope="session")
def capdyn_bin():
    if not os.access(BIN, os.X_OK):
        pytest.fail(f"the capdyn command {BIN} is not built (make python-test builds it)")
    return BIN


def run_cli(*args, cwd=None):
    """Runs the capdyn command; returns stdout (fails the test on a non-zero exit)."""
    p = subprocess.run([BIN, *args], capture_output=True, text=True, cwd=cwd)
    assert p.returncode == 0, f"capdyn {' '.join(args)} exited {p.returncode}: {p.stderr}"
    return p.stdout
