"""The table engine: the checker's BFS with every distinct reaction run once.

The direct engine (:mod:`desmon.verify.direct`) runs the real deployment core for each
transition, and most of those runs repeat one another: a reaction reads the context, the
deployments and the standing errors, and of the platforms only which of them pass the
requirement checks it asks about. This engine runs the same real core once per distinct
reading, on opaque platform handles whose checks record what the run uses of them
(:mod:`~desmon.verify.table.recording`, :mod:`~desmon.verify.table.observed`), keeps each
run as a path of a decision tree (:mod:`~desmon.verify.table.tree`) and walks the trees
for every other transition, answering the checks from per-platform tables
(:mod:`~desmon.verify.table.tables`). States are integers
(:mod:`~desmon.verify.table.encoding`), events, tree walks and duplicate detection numpy
operations over a batch of a BFS level (:mod:`~desmon.verify.table.search`). The result
(states and their order, transitions, every counter, counterexamples) is the direct
engine's (``tests/test_verify_table.py``); why that holds, and what it assumes beyond the
determinism of a reaction, is in docs/design.md ("Why the table engine is sound").
Symmetry reduction is left to the direct engine.
"""

from desmon.deployment.ports import QUERY_METHODS
from desmon.errors import TableUnsupported, UnobservedRead
from desmon.verify.table.encoding import MAX_DIGITS
from desmon.verify.table.search import CHUNK_STATES, TableEngine, table_unsupported

__all__ = ["TableEngine", "TableUnsupported", "UnobservedRead", "table_unsupported", "CHUNK_STATES", "MAX_DIGITS", "QUERY_METHODS"]

