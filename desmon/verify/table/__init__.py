"""The table engine: the checker's BFS with every distinct reaction run once.

The direct engine (:mod:`desmon.verify.direct`) runs the real deployment core for each of the millions of
transitions of a large scenario. Most of those runs repeat one another: a reaction reads
the context, the deployments and the standing errors, and of the platforms only *which
of them pass the requirement checks* it asks about. This engine runs the same real
core, but only once per distinct reading, and replays what it did everywhere else.

How a reaction is memoised
    A state is an environment code (context and the current requirements of each graph
    that requirement changes reach, as one *global* digit; failed devices, platforms down
    or absent (on demand), load levels: one mixed-radix digit per platform) and an
    interned system part (deployments, standing errors). A transition's *root* is
    (system part, global digit after the event, what the event changed, failed-start
    prefix). The first time a root is
    met, the real core runs on the real state with the recording Checks port
    (:class:`~desmon.verify.table.recording.RecordingChecks`), which
    answers every requirement check with the real result, wrapped so that what the run *uses* of it is recorded:
    whether one platform is acceptable, the acceptable platforms one by one in preference
    order as far as the run iterates, or every answer down to the failure texts (see
    :class:`~desmon.verify.table.recording.RecordingChecks`). With preferences the order of the acceptable platforms, their
    scores, gains and score breakdown derive from every platform's score: using them
    observes each platform's *score key* (rejected, or the number of its (score,
    breakdown) among those the platform's facts can give). The run becomes a path in a decision tree: one node per
    observation, one branch per answer, a leaf with what the reaction did (next system
    part, start outcomes, deployer branches, an instantaneous violation). Other
    transitions with the same root walk the tree; each observation is answered from a
    table of per-platform results (computed by the same requirement code on the same
    platform facts, indexed by the platform's digit), and a leaf gives the successor. A
    transition whose answers leave the tree runs the real core again, which extends the
    tree. The invariants of each new state are memoised the same way, on (system part,
    context). Events, tree walks and duplicate detection are numpy operations over a
    batch of a BFS level.

Why it is sound
    A reaction is a deterministic function of what it reads through the ports (the
    checker already relies on that: a replay that disagrees is reported as
    nondeterminism). The context, deployments and standing errors are in the root, the
    requirement checks are observed, and the platforms' facts cannot be read any other
    way: while a run is recorded the core's Query port offers only the QueryPort
    methods, and its platform states are opaque handles
    (:class:`~desmon.deployment.ports.PlatformHandle`) that hold no run-time facts:
    reading ``up``, ``devices`` or ``load`` (or comparing two states) raises
    :class:`~desmon.errors.UnobservedRead` (``--engine auto`` then falls back to the
    direct engine). A check on facts that are not the state's own (a port that
    rewrites them, or swaps the platform) is refused the same way, and so is a
    check's result used as what its wrapper is not. Every recording re-checks
    the environment code and the stimulus, and a recording that contradicts the tree is
    a :class:`~desmon.errors.NondeterminismError`. Assumed beyond determinism: a
    reaction does not branch on the *type* of a check's result (the wrappers are not
    tuples or strings) or on a platform state's hash value (handles hash by
    identity). Counterexamples are rebuilt by replaying their
    events through the real core, as in the direct engine.

The result (states and their order, transitions, every counter, counterexamples) is
the direct engine's, for every scenario shipped (``tests/test_verify_table.py``).
Symmetry reduction is left to the direct engine.

The package's parts: :mod:`~desmon.verify.table.encoding` (environment codes and
events as array operations), :mod:`~desmon.verify.table.tables` (per-digit answers of
the requirement checks), :mod:`~desmon.verify.table.recording` (recorded runs of the
real core), :mod:`~desmon.verify.table.tree` (decision trees) and
:mod:`~desmon.verify.table.search` (the BFS).
"""

from desmon.errors import TableUnsupported, UnobservedRead
from desmon.verify.table.recording import QUERY_METHODS
from desmon.verify.table.search import CHUNK_STATES, MAX_DIGITS, TableEngine, table_unsupported

__all__ = ["TableEngine", "TableUnsupported", "UnobservedRead", "table_unsupported", "CHUNK_STATES", "MAX_DIGITS", "QUERY_METHODS"]

