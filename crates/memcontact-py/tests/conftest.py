"""Shared fixtures: the repository, its examples, and the command-line tool."""

import os
import subprocess
from pathlib import Path

import pytest
from hypothesis import settings

# Hypothesis: few examples in the test command; HYPOTHESIS_PROFILE=long for a long run.
settings.register_profile("default", max_examples=25, deadline=10_000)
settings.register_profile(
    "long", max_examples=int(os.environ.get("HYPOTHESIS_EXAMPLES", "5000")), deadline=None
)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "default"))

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
