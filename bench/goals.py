"""The benchmarks' goals in one table, their small configurations, and the RESULT line.

Every ``bench/bench_*.py`` ends its output with one line ``RESULT key=value ...``;
:data:`GOALS` says which of those figures has a goal (what it asks, in the note),
:data:`QUICK` the options of each bench's small configuration (``python -m bench
--quick``, ``tests/test_benches.py``). ``python -m bench`` (:mod:`bench.__main__`)
runs them and compares. :data:`RESULT_KEYS` lists the keys each RESULT line carries:
the figures the README and docs quote are marked with them and rewritten from the
benches' runs (:mod:`bench.figures`).
"""

from __future__ import annotations

import operator
from typing import Callable, NamedTuple

__all__ = ["Goal", "GOALS", "QUICK", "BENCHES", "RESULT_KEYS", "OPTIONAL_KEYS", "result_mode", "unexpected_keys", "parse_result", "missed", "BenchError"]


class BenchError(Exception):
    """A bench whose output has no RESULT line to compare (it is broken)."""


class Goal(NamedTuple):
    key: str  # the RESULT key
    op: str  # ">=", "<=", "<" or ">"
    value: float
    note: str = ""

    def met(self, figure: float) -> bool:
        return _OPS[self.op](figure, self.value)

    def __str__(self) -> str:
        return f"{self.key} {self.op} {self.value:g}"


_OPS: dict[str, Callable[[float, float], bool]] = {">=": operator.ge, "<=": operator.le, "<": operator.lt, ">": operator.gt}

#: bench module -> the goals of its RESULT figures (on its full configuration)
GOALS: dict[str, tuple[Goal, ...]] = {
    "bench_analyze": (Goal("build_ratio", "<=", 2, "the chain's build at most twice the checker's exploration"),),
    "bench_sim": (
        Goal("x_real_time", ">=", 5000, "the 8 h robot day at 5,000x real time or more"),
        Goal("ratio_bare", "<=", 100, "at most 100x the bare SimPy cost of the same events"),
        Goal("signals_off_s", "<", 1.5, "the day with signals off under 1.5 s"),
    ),
    "bench_scale": (Goal("bytes_per_state", "<=", 24, "the scale family's largest N (6 by default) at most 24 bytes of resident memory per state"),),
    "bench_verify": (
        Goal("states_per_s", ">=", 100_000, "the fallback-heavy model at 100,000 states/s on one core"),
        Goal("bytes_per_state", "<=", 150, "at most 150 bytes of resident memory per state"),
    ),
    "bench_estimate": (
        Goal("minutes_2_cores", "<=", 5, "the coffee shift's exposure to +-1 % at 99 %, guaranteed, on 2 cores"),
        Goal("speedup", ">=", 1.8, "2 Dask workers vs 1 on 2 idle cores"),
    ),
    "bench_sweep": (
        Goal("speedup", ">=", 1.8, "2 Dask workers vs 1 on 2 idle cores"),
        Goal("overhead", "<", 0.05, "Dask vs the bare loop"),
    ),
    "bench_suite": (Goal("tests_min", "<=", 6, "make test, from a clean clone, in at most 6 minutes of tests on 2 cores"),),
    "bench_validity": (
        Goal("seconds", "<", 1.0, "acceptable sets of every spec"),
        Goal("reasons_max_ms", "<", 50.0, "every reason for the slowest spec"),
    ),
}

#: bench module -> its options in the small configuration (a smoke run of seconds)
QUICK: dict[str, tuple[str, ...]] = {
    "bench_analyze": ("--quick",),
    "bench_detectors": ("--trials", "10", "--hours", "0.02"),
    "bench_estimate": ("--quick",),
    "bench_fleet": ("--robots", "3", "--edges", "1", "--hours", "0.1"),
    "bench_preferences": ("--quick",),
    "bench_scale": ("--max-platforms", "3", "--time-limit", "120"),
    "bench_sim": ("--until", "600"),
    "bench_suite": ("--quick",),
    "bench_sweep": ("--hours", "0.02", "--seeds", "1"),
    "bench_table_prefs": ("--quick", "--repeat", "1"),
    "bench_upgrade": ("--seeds", "1", "--hours", "0.2"),
    "bench_validity": ("--platforms", "300", "--specs", "30", "--scalar-specs", "5", "--reason-specs", "2", "--events", "20"),
    "bench_verify": ("--quick",),
}

#: every bench, in the order ``python -m bench`` runs them
BENCHES: tuple[str, ...] = tuple(sorted(QUICK))

#: the keys of each bench's RESULT line, by mode: ``"bench_x"`` is its usual run (any
#: options but a mode's), ``"bench_x --flag"`` the run with that option, whose RESULT line
#: differs. ``python -m bench`` reports a bench whose RESULT line lacks one of these keys
#: or carries another as broken, and the docs' figure markers may name only these keys
#: (``tests/test_figures.py``), so the list cannot rot silently.
RESULT_KEYS: dict[str, tuple[str, ...]] = {
    "bench_analyze": (
        "states", "build_s", "explore_s", "build_ratio", "build_per_state_ratio", "steady_s", "transient_s", "exact_s", "sim_mean_s", "sim_ci_low",
        "sim_ci_high", "storm_steady_s", "storm_transient_s",
    ),
    "bench_analyze --large": ("states", "build_s", "steady_s", "transient_s", "solve_s", "peak_mb"),
    "bench_analyze --phases-error": ("phases_error_most",),
    "bench_analyze --agreement": ("scenarios", "inside", "seeds"),
    "bench_analyze --methods": ("chains", "crossover_jumps", "krylov_speedup_at_4000", "krylov_speedup_at_16000", "max_difference"),
    "bench_analyze --undetected": ("scenarios", "inside", "seeds", "trials"),
    "bench_detectors": ("trials_per_s", "eval_ratio", "missions_per_s", "detectors_us_per_sim_s"),
    "bench_estimate": (
        "robot_day_runs_per_min_core", "coffee_shift_runs_per_min_core", "runs_needed_1pct_99", "runs_needed_horizon_range", "runs_needed_unsized_bets", "clt_runs_needed",
        "floor_runs",
        "minutes_2_cores", "speedup", "one_worker_s", "two_workers_s", "coffee_shift_full_s", "coffee_shift_read_s", "coffee_shift_read_ratio",
        "robot_day_full_s", "robot_day_read_s", "robot_day_read_ratio",
    ),
    "bench_estimate --coverage": (
        "scenarios", "estimations", "runs", "guaranteed_passed", "guaranteed_held_min", "narrowed_held_min", "normal_held_min",
        "narrowed_normal_failed", "halved_failed",
    ),
    "bench_fleet": (
        "seconds", "realtime_ratio", "peak_mb", "robots", "edges", "hours", "per_robot_vs_alone", "reactions_per_s", "violations", "events",
        "bare_s", "ratio_bare",
    ),
    "bench_preferences": ("pref_time_ratio", "exposure_with_lease", "exposure_without_lease"),
    "bench_sim": (
        "x_real_time", "ratio_bare", "signals_off_s", "wall_s", "bare_s", "events", "until_s", "serial_s", "serial_ratio_bare", "cpu_s", "sim_cpu_s", "ahead_blocks",
    ),
    "bench_scale": ("platforms", "states", "transitions", "seconds", "cpu_seconds", "states_per_s", "bytes_per_state", "growth"),
    "bench_scale --breakdown": ("platforms", "seconds", "walk_s", "recording_s", "seen_s", "events_s", "serial_share", "two_workers_bound"),
    "bench_suite": ("passed", "skipped", "failed", "total_min", "tests_min", "install_min", "cpu_min", "test_cpu_s"),
    "bench_sweep": ("speedup", "overhead", "runs", "hours", "bare_s", "one_worker_s", "two_workers_s"),
    "bench_sweep --scheduler": ("per_task_ratio", "in_task_ratio", "cpu_ratio", "runs", "hours", "rounds", "workers", "threads"),
    "bench_table_prefs": ("cloud_ratio", "cloud_wide_ratio", "pref_median_ratio"),
    "bench_upgrade": (
        "seeds", "hours", "exposure_bbm", "exposure_keep", "exposure_diff_mean", "exposure_diff_min", "exposure_diff_max",
        "upgrades_per_run", "upgrade_blind_s_per_run",
    ),
    "bench_validity": ("seconds", "scalar_ratio", "reasons_max_ms", "reasons_ratio"),
    "bench_verify": (
        "states_per_s", "bytes_per_state", "records", "states_per_cpu_s", "fallback_states", "fallback_transitions",
        "fallback_seconds", "fallback_peak_mb", "fallback_ratio", "stale_states", "4p_states", "4p_ratio", "6p_states", "6p_ratio",
    ),
}

#: keys of :data:`RESULT_KEYS` a RESULT line may lack (Storm's figures: only with stormpy installed)
OPTIONAL_KEYS: frozenset[str] = frozenset({"storm_steady_s", "storm_transient_s"})


def result_mode(name: str, args: tuple[str, ...] | list[str]) -> str:
    """The :data:`RESULT_KEYS` entry of ``python -m bench.<name> <args>``: ``name``, or
    ``"name --flag"`` when one of ``args`` is a flag whose run prints other keys."""
    for arg in args:
        mode = f"{name} {arg.partition('=')[0]}"
        if mode in RESULT_KEYS:
            return mode
    return name


def unexpected_keys(mode: str, figures: dict[str, float | str]) -> list[str]:
    """What differs between a RESULT line's keys and :data:`RESULT_KEYS` ``[mode]`` (empty: nothing)."""
    declared = RESULT_KEYS.get(mode, ())
    lacking = [k for k in declared if k not in figures and k not in OPTIONAL_KEYS]
    extra = [k for k in figures if k not in declared]
    return ([f"lacks {', '.join(lacking)}"] if lacking else []) + ([f"carries {', '.join(extra)}, not in bench/goals.py RESULT_KEYS[{mode!r}]"] if extra else [])


def parse_result(output: str) -> dict[str, float | str]:
    """The figures of a bench's last line ``RESULT key=value ...`` (numbers as floats)."""
    lines = [ln for ln in output.splitlines() if ln.strip()]
    if not lines or not lines[-1].startswith("RESULT "):
        raise BenchError("its output does not end with a RESULT line" + (f" (last line: {lines[-1][:120]!r})" if lines else " (no output)"))
    out: dict[str, float | str] = {}
    for item in lines[-1].split()[1:]:
        key, eq, value = item.partition("=")
        if not eq or not key:
            raise BenchError(f"RESULT item {item!r} is not key=value")
        try:
            out[key] = float(value)
        except ValueError:
            out[key] = value
    return out


def missed(bench: str, figures: dict[str, float | str]) -> list[str]:
    """The goals of ``bench`` its figures miss (or lack), one line each."""
    out = []
    for goal in GOALS.get(bench, ()):
        figure = figures.get(goal.key)
        if not isinstance(figure, float):
            out.append(f"{bench}: {goal}: no figure {goal.key} in its RESULT line")
        elif not goal.met(figure):
            out.append(f"{bench}: {goal}: measured {figure:g}")
    return out
