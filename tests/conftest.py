"""Shared fixtures: paths, the published seed cases, designs."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

import gearopt

ROOT = Path(__file__).resolve().parents[1]
STUDIES = ROOT / "studies"
TOY = Path(__file__).parent / "toy_plugin"
#: the seeds' published inputs and outputs (provenance: tests/data/README.md)
SEED_CASES = Path(__file__).parent / "data" / "seed_cases.json"


@pytest.hookimpl(tryfirst=True)
def pytest_sessionstart(session):
    """Every kernel compiled (after an install: in two processes, :mod:`gearopt.warmup`) or
    loaded once by pytest-xdist's controller before it starts the test processes (or by the
    one process without xdist): they then load the cache rather than each compile the same
    kernels side by side."""
    if hasattr(session.config, "workerinput"):  # a test process: its controller did it
        return
    from gearopt.warmup import warm_kernels

    warm_kernels()


@pytest.fixture(scope="session", autouse=True)
def _compiled_kernels():
    """The compiled kernels (contact engine, mesh cycle, loaded contact) compiled (or loaded
    from the disk cache) once in this process before any test starts a subprocess: CLI and
    study workers then load the cache rather than compile it side by side."""
    from gearopt.contact import kernel_warmup as contact_kernels
    from gearopt.loaded import kernels as loaded_kernels
    from gearopt.mesh import handover_kernels, side_kernels
    from gearopt.mesh import kernels as mesh_kernels

    contact_kernels.warm()
    mesh_kernels.warm()
    handover_kernels.warm()
    side_kernels.warm()
    loaded_kernels.warm()


@pytest.fixture(scope="session")
def seed_cases() -> dict:
    """The seeds' published inputs and outputs (tests/data/seed_cases.json)."""
    return json.loads(SEED_CASES.read_text())


@pytest.fixture(scope="session")
def table3_design() -> gearopt.Design:
    return gearopt.load_design(STUDIES / "seed001_table3.toml")


@pytest.fixture(scope="session")
def table3_text() -> str:
    return (STUDIES / "seed001_table3.toml").read_text()


@pytest.fixture(scope="session")
def toy_site(tmp_path_factory):
    """The toy third-party distribution, pip-installed into a folder of its own."""
    target = tmp_path_factory.mktemp("toy_site")
    subprocess.run(
        [
            sys.executable,
            "-m",
            "pip",
            "install",
            "--quiet",
            "--no-deps",
            "--no-build-isolation",
            "--target",
            str(target),
            str(TOY),
        ],
        check=True,
        capture_output=True,
    )
    return target
