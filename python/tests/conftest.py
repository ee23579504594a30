"""Shared fixtures of the Python package's tests (run by `.ci/run` on the installed wheel).

They need the installed package, numpy, pandas, meshio, matplotlib, dask[distributed] and the
`ricochet` binary (`target/release/ricochet`, or RICOCHET_BIN), to compare the package with the
command line. Without one of them the tests fail with a message naming it when CI is set, and are
skipped, with the reason shown, otherwise.
"""

from __future__ import annotations

import importlib
import os
import subprocess
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
ASSETS = REPO / "assets"
DATA = Path(__file__).resolve().parent / "data"
NEEDED = ["ricochet", "numpy", "pandas", "meshio", "matplotlib", "dask.distributed"]


def _binary() -> Path:
    return Path(os.environ.get("RICOCHET_BIN", REPO / "target" / "release" / "ricochet"))


def _missing() -> list[str]:
    missing = []
    for name in NEEDED:
        try:
            importlib.import_module(name)
        except ImportError as e:
            missing.append(f"{name} ({e})")
    if not _binary().is_file():
        missing.append(f"the ricochet binary at {_binary()} (cargo build --release, or set RICOCHET_BIN)")
    return missing


MISSING = _missing()


def pytest_configure(config: pytest.Config) -> None:
    if MISSING and os.environ.get("CI"):
        raise pytest.UsageError(
            "CI is set but the Python tests cannot run: missing " + "; ".join(MISSING)
            + " (pip install ./python pandas meshio matplotlib 'dask[distributed]' pytest)"
        )


def pytest_report_header(config: pytest.Config) -> list[str]:
    if MISSING:
        return ["NOTICE: the ricochet Python tests are SKIPPED: missing " + "; ".join(MISSING)]
    return []


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    if MISSING:
        skip = pytest.mark.skip(reason="missing " + "; ".join(MISSING))
        for item in items:
            item.add_marker(skip)


@pytest.fixture(scope="session")
def binary() -> Path:
    """The `ricochet` command line."""
    return _binary()


@pytest.fixture(scope="session")
def cli(binary: Path):
    """Runs `ricochet ARGS` and returns the completed process (its output captured)."""

    def run(*args: object, check: bool = True) -> subprocess.CompletedProcess[str]:
        env = dict(os.environ, XDG_RUNTIME_DIR=os.environ.get("XDG_RUNTIME_DIR", "/tmp"))
        p = subprocess.run([os.fspath(binary), *map(os.fspath, args)], capture_output=True, text=True, env=env)
        if check and p.returncode != 0:
            raise AssertionError(f"ricochet {' '.join(map(str, args))} exited {p.returncode}:\n{p.stderr}")
        return p

    return run
