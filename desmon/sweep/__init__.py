"""Design-space sweeps on Dask: a grid of scenario parameters x seeds, one table row per run.

``desmon sweep SCENARIO -p hand_memory=256,384 -p wrench_mttf=600,1800 --seeds 50 -o results.parquet``
runs every combination (a *point*) with 50 seeds each, as Dask tasks on a local cluster
(all cores) or on an existing one (``--scheduler tcp://HOST:PORT``), and writes a tidy
table (Parquet or CSV): :mod:`desmon.sweep.grid` (the grid and each run's seed),
:mod:`desmon.sweep.jobs` (one run in a worker), :mod:`desmon.sweep.runner` (Dask),
:mod:`desmon.sweep.table` (columns, journal, resume), :mod:`desmon.sweep.core`
(:func:`~desmon.sweep.core.run_sweep`), :mod:`desmon.sweep.plot` (``desmon sweep-plot``).
Dask, pandas and pyarrow (the ``sweep`` extra) are imported only when a sweep runs.
See docs/sweeps.md.
"""

from desmon.sweep.grid import Axis, Grid, Point, Run, SweepError, derive_seed, parse_axes

__all__ = ["Axis", "Grid", "Point", "Run", "SweepError", "derive_seed", "parse_axes"]
