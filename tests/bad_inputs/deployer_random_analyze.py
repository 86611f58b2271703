# args: analyze {root}/scenarios/coffee_shift.py -p faults=False --horizon 60 --trials 1 --no-progress --deployer {case}:coin_flip --json {tmp}/a.json
# exit: 2
# expect: deployer {case}:coin_flip is nondeterministic
# expect: it issued first [
# expect: ], then [
# untouched: {tmp}/a.json
"""A bad-input case: see tests/test_bad_inputs.py. A deployer that decides at random, analyzed: the chain's
reactions are checked for determinism as desmon verify checks them, so its figures (which would change from
run to run) are refused, not printed."""
import random

from desmon.deployment.ports import Start

_coin = random.Random(1)


def coin_flip(q, slots, changed, context_changed):  # type: ignore[no-untyped-def]
    for slot in slots:
        platforms = [s.name for s in q.platform_states()]
        yield Start(_coin.choice(slot), _coin.choice(platforms))
