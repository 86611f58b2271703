# args: verify {root}/scenarios/coffee_handover.py --deployer {case}:coin_flip
# exit: 2
# expect: deployer {case}:coin_flip is nondeterministic
# expect: it issued first [
# expect: ], then [
"""A bad-input case: see tests/test_bad_inputs.py. A deployer that decides at random (here: seeded, so the case
is reproducible): the same state and event give different commands; it is refused, not HOLDS."""
import random

from desmon.deployment.ports import Start

_coin = random.Random(1)


def coin_flip(q, slots, changed, context_changed):  # type: ignore[no-untyped-def]
    for slot in slots:
        platforms = [s.name for s in q.platform_states()]
        yield Start(_coin.choice(slot), _coin.choice(platforms))
