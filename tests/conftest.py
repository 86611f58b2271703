from pathlib import Path
from typing import Callable

import pytest

from desmon.errors import DesmonError

ROOT = Path(__file__).resolve().parent.parent


@pytest.fixture(scope="session")
def root() -> Path:
    return ROOT


def refused(error: type[DesmonError], build: Callable[[], object]) -> str:
    """The message of the ``error`` that ``build()`` raises; it must be one line."""
    with pytest.raises(error) as info:
        build()
    msg = str(info.value)
    assert "\n" not in msg
    return msg


# Hypothesis draws its examples from a fixed seed here: the same suite explores the same
# sequences on every machine, so CI is reproducible (desmon fuzz takes --seed for users).
from hypothesis import settings  # noqa: E402

settings.register_profile("desmon", derandomize=True, deadline=None)
settings.load_profile("desmon")
