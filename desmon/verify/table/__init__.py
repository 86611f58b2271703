"""The table engine: the checker's BFS with every distinct reaction run once.

The direct engine (:mod:`desmon.verify.direct`) runs the real deployment core for each
transition; this engine runs it once per distinct reading of a reaction (the context,
the deployments, the standing errors, and which platforms pass the requirement checks it
asks about), keeps each run as a path of a decision tree and walks the trees for every
other transition, a batch of a BFS level at a time with numpy. Its result is the direct
engine's (``tests/test_verify_table.py``). How it works: docs/findings.md ("How the table
engine works"); why it is sound: docs/design.md ("Why the table engine is sound").
Under ``--symmetry`` it stores canonical codes (:mod:`desmon.verify.orbits`).
"""

from desmon.verify.table.search import CHUNK_STATES, TableEngine, table_unsupported

__all__ = ["TableEngine", "table_unsupported", "CHUNK_STATES"]

