"""``desmon verify --stats``: states/s, bytes/state and the recorded runs, only when asked."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from desmon.cli import main
from desmon.loader import load_scenario
from desmon.verify import Checker
from desmon.verify.arrays import IntTable

SCENARIO = str(Path(__file__).resolve().parents[1] / "scenarios" / "fallbacks.py")


def test_stats_line_and_json_key_only_with_the_flag(tmp_path, capsys):
    plain, stats = tmp_path / "plain.json", tmp_path / "stats.json"
    assert main(["verify", SCENARIO, "--no-progress", "--json", str(plain)]) == 0
    out = capsys.readouterr().out
    assert "stats:" not in out and "bytes/state" not in out
    assert "stats" not in json.loads(plain.read_text())
    assert main(["verify", SCENARIO, "--no-progress", "--stats", "--json", str(stats)]) == 0
    out = capsys.readouterr().out
    line = next(ln for ln in out.splitlines() if ln.startswith("stats: "))
    got = json.loads(stats.read_text())
    assert f"{got['records']:,} recorded runs of the core (table engine)" in line and "bytes/state" in line and "states/s" in line
    assert set(got["stats"]) == {"states_per_s", "bytes_per_state", "start_mb", "peak_mb", "records"}
    assert got["stats"]["records"] == got["records"] and got["stats"]["bytes_per_state"] >= 0
    # the report itself is the same with and without --stats
    assert {k: v for k, v in got.items() if k not in ("stats", "seconds", "peak_mb")} == {
        k: v for k, v in json.loads(plain.read_text()).items() if k not in ("seconds", "peak_mb")
    }


def test_stats_of_the_direct_engine_name_no_recorded_runs(capsys):
    assert main(["verify", SCENARIO, "--no-progress", "--stats", "--engine", "direct", "--max-states", "30"]) == 3
    line = next(ln for ln in capsys.readouterr().out.splitlines() if ln.startswith("stats: "))
    assert "recorded runs" not in line


def test_stats_sets_up_a_search_not_a_replay(tmp_path, capsys):
    cex = tmp_path / "cex.json"
    cex.write_text("{}")
    assert main(["verify", SCENARIO, "--replay", str(cex), "--stats"]) == 2
    assert "--stats sets up a search, and --replay replays one saved counterexample instead: drop --stats" in capsys.readouterr().err


def test_bytes_per_state_is_the_memory_the_search_added_per_state():
    r = Checker(load_scenario(SCENARIO), "desmon").run()
    assert r.start_mb > 0 and r.bytes_per_state >= 0  # (the peak and the resident size are read two ways: about equal)
    assert r.bytes_per_state == pytest.approx(max(r.peak_mb - r.start_mb, 0) * 2**20 / r.states)


def test_int_table_is_a_set_and_a_map_through_growth():
    t = IntTable(bits=2)
    keys = [5, 1 << 40, 0, 77, 12345678901]
    import numpy as np

    t.add(np.array(keys[:2]), np.array([10, 20]))
    t.add(np.array(keys[2:]), np.array([30, 40, 50]))
    assert len(t) == 5
    assert t.get(np.array([77, 5, 6, 0, 1 << 40])).tolist() == [40, 10, -1, 30, 20]
    s = IntTable(bits=1, values=False)
    s.add(np.arange(0, 3000, 3))
    assert s.contains(np.array([0, 3, 4, 2997, 3000])).tolist() == [True, True, False, True, False]


def test_int_table_answers_as_a_dict_along_long_probes():
    # lookups read the key their probe ends at as they go (no second read of the slots):
    # random batches, tables kept small so that probes run long, present and absent keys
    import numpy as np

    rng = np.random.default_rng(1)
    for trial in range(20):
        t = IntTable(bits=3, values=bool(trial % 2))
        ref: dict[int, int] = {}
        for _ in range(15):
            ks = np.unique(rng.integers(0, 1 << int(rng.integers(3, 40)), int(rng.integers(0, 400))))
            ks = np.array([k for k in ks.tolist() if k not in ref], dtype=np.int64)
            rng.shuffle(ks)
            vs = rng.integers(0, 100, len(ks))
            t.add(ks, vs if t.vals is not None else None)
            ref.update(zip(ks.tolist(), vs.tolist()))
            q = np.concatenate([ks, rng.integers(0, 1 << 40, 200)])
            assert t.contains(q).tolist() == [k in ref for k in q.tolist()]
            if t.vals is not None:
                assert t.get(q).tolist() == [ref.get(k, -1) for k in q.tolist()]
