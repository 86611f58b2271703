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


def pytest_terminal_summary(terminalreporter) -> None:  # type: ignore[no-untyped-def]
    """A browser test that could not run says so on one line at the end of every run
    (not only under ``-rs``): tests/test_explore.py skips with "browser test not run: ..."."""
    reasons = set()
    for report in terminalreporter.stats.get("skipped", []):
        longrepr = getattr(report, "longrepr", None)
        text = longrepr[2] if isinstance(longrepr, tuple) and len(longrepr) == 3 else str(longrepr)
        if "browser test not run: " in text:
            reasons.add(text[text.index("browser test not run: "):])
    for reason in sorted(reasons):
        terminalreporter.write_line(f"desmon: {reason}", yellow=True, bold=True)
