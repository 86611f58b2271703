"""Symmetry reduction (``--symmetry``): currently refuses, with the reason.

Permuting interchangeable platforms is sound only if the transition relation commutes
with the permutation. Both deployers break ties among acceptable platforms by
preference, then declaration order (DESIGN.md §4), so whenever two interchangeable
platforms are acceptable at once the choice is *not* symmetric and the reduction would
merge states with different futures. Until a permutation-checked reduction lands, the
checker refuses rather than give a possibly wrong verdict.
"""

from __future__ import annotations

from typing import Any

from desmon.errors import CheckerError

__all__ = ["Symmetry"]


class Symmetry:
    def __init__(self, checker: Any) -> None:
        groups = checker.bounds.interchangeable
        if not groups:
            raise CheckerError(
                f"--symmetry: scenario {checker.scenario.name!r} declares no interchangeable platforms "
                "(Bounds(interchangeable=((...),)))"
            )
        raise CheckerError(
            f"--symmetry refused for {', '.join('/'.join(g) for g in groups)}: the {checker.deployer_name} deployer breaks "
            "ties by declaration order, which is not symmetric in these platforms; run without --symmetry"
        )
