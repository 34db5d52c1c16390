"""Shared fixtures: paths, the published seed cases, designs."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

import gearopt

ROOT = Path(__file__).resolve().parents[1]
STUDIES = ROOT / "studies"
TOY = Path(__file__).parent / "toy_plugin"
SEED_CASES = ROOT.parent / "shared" / "reference" / "seed_cases.json"


@pytest.fixture(scope="session", autouse=True)
def _compiled_kernels():
    """The contact engine's kernels compiled (or loaded from the disk cache) once in this
    process before any test starts a subprocess: CLI and study workers then load the cache
    rather than compile it side by side."""
    from gearopt.contact import kernels as contact_kernels

    contact_kernels.warm()


@pytest.fixture(scope="session")
def seed_cases() -> dict:
    """The seeds' published inputs and outputs (../shared/reference/seed_cases.json).

    CI always has ../shared; elsewhere the published-number tests are skipped if it is missing.
    """
    if not SEED_CASES.exists():
        if os.environ.get("CI"):
            pytest.fail(f"{SEED_CASES} is missing on CI")
        pytest.skip(f"{SEED_CASES} not found (the shared folder beside the project)")
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
