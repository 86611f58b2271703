from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent


@pytest.fixture(scope="session")
def root() -> Path:
    return ROOT


# Hypothesis draws its examples from a fixed seed here: the same suite explores the same
# sequences on every machine, so CI is reproducible (desmon fuzz takes --seed for users).
from hypothesis import settings  # noqa: E402

settings.register_profile("desmon", derandomize=True, deadline=None)
settings.load_profile("desmon")
