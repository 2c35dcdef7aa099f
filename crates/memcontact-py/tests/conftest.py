"""Shared fixtures: the repository, its examples, and the command-line tool."""

import os
import subprocess
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[3]
EXAMPLES = REPO / "examples"


@pytest.fixture(scope="session")
def examples() -> Path:
    return EXAMPLES


@pytest.fixture(scope="session")
def cli() -> Path:
    """The release binary `memcontact`: MEMCONTACT_BIN, or target/release/memcontact
    brought up to date with cargo (a no-op when it is)."""
    given = os.environ.get("MEMCONTACT_BIN")
    if given:
        return Path(given)
    subprocess.run(
        ["cargo", "build", "--release", "-q", "-p", "memcontact-cli"], cwd=REPO, check=True
    )
    return REPO / "target" / "release" / "memcontact"
