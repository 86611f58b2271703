"""The sweep's table: one row per (point, seed), its columns and types, the journal the
rows are appended to as they finish, and the Parquet / CSV files written from it.

Columns, in order: ``point`` (index in the grid), ``seed_index``, ``seed`` (derived, see
:mod:`desmon.sweep.grid`), one column per swept parameter, ``scenario``, ``job``,
``deployer``, the job's settings (``until`` / ``max_states`` / ``examples`` / ``trials`` /
``phases``, ``horizon``, ``max_states``),
``exit_code``, ``error`` (empty unless the run failed), the job's figures
(:data:`desmon.sweep.jobs.METRICS`, then ``errors_<kind>`` and ``memory_peak_mb_<platform>``
for ``run``), and last ``wall_s``: the run's wall-clock seconds, the one column that
differs between two runs of the same sweep.

pandas and pyarrow are imported inside the functions: ``import desmon`` does not need them.
"""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import IO, Any, Iterable, Sequence

from desmon.sweep.grid import Axis, Grid, Run, SweepError, derive_seed
from desmon.sweep.jobs import METRICS

__all__ = [
    "FORMAT", "TABLE_SUFFIXES", "journal_path", "Journal", "read_journal", "read_table", "write_table", "columns_of",
    "key_of_row", "check_same_sweep", "frame",
]

FORMAT = 1
TABLE_SUFFIXES = (".parquet", ".csv")
_HEAD = ("point", "seed_index", "seed")
_STR_METRICS = {"verdict", "violated", "error", "top_state", "status", "method"}
#: analyze's figures that are numbers with a fraction but whose names do not say so
_FLOAT_METRICS = {
    "exposure_s_per_hour", "exposure_s_per_mission", "undetected_slips_per_hour", "p_exposure_within_T",
    "long_run_unmonitored_fraction", "top_state_s_per_hour",
    "estimate", "low", "high", "half_width", "normal_low", "normal_high", "min_value", "max_value", "range_low", "range_high",  # estimate's
}


def journal_path(output: str | os.PathLike[str]) -> Path:
    """The journal beside ``output`` (``results.parquet`` -> ``results.parquet.journal.jsonl``)."""
    p = Path(output)
    return p.with_name(p.name + ".journal.jsonl")


def _is_float(column: str) -> bool:
    return column in _FLOAT_METRICS or column.endswith(("_s", "_s_per_hour", "_s_per_mission")) or column.startswith("memory_peak_mb_") or "_rate_" in column or column.startswith(("tp_rate", "fp_rate"))


def columns_of(axes: Sequence[Axis], job: str, settings: Sequence[str], rows: Iterable[dict[str, Any]]) -> list[str]:
    """The table's columns: the fixed ones in order, then the per-run ones (errors_<kind>,
    memory_peak_mb_<platform>) sorted, then ``wall_s``."""
    fixed = [*_HEAD, *(a.name for a in axes), "scenario", "scenario_digest", "job", "deployer", *settings, "exit_code", "error", *METRICS[job]]
    extra = sorted({k for r in rows for k in r} - set(fixed) - {"wall_s"})
    return [*fixed, *extra, "wall_s"]


def frame(rows: Sequence[dict[str, Any]], axes: Sequence[Axis], job: str, settings: Sequence[str]) -> Any:
    """``rows`` as a pandas DataFrame, sorted by (point, seed_index), with stable column types."""
    import pandas as pd

    rows = sorted(rows, key=lambda r: (r["point"], r["seed_index"]))
    cols = columns_of(axes, job, settings, rows)
    df = pd.DataFrame.from_records([{c: r.get(c) for c in cols} for r in rows], columns=cols)
    kinds = {a.name: a.kind for a in axes}
    for c in cols:
        if c in _HEAD or c == "exit_code":
            df[c] = df[c].astype("int64")
        elif c in kinds:
            df[c] = df[c].astype({"int": "int64", "float": "float64", "bool": "bool", "str": "object"}[kinds[c]])
        elif c in ("scenario", "scenario_digest", "job", "deployer") or c in _STR_METRICS:
            df[c] = df[c].astype("object")
        elif c in settings:
            continue
        elif c == "wall_s" or _is_float(c):
            df[c] = pd.to_numeric(df[c], errors="coerce").astype("float64")
        elif c.startswith("errors_"):
            counts = pd.to_numeric(df[c], errors="coerce").fillna(0).astype("Int64")
            counts[df["error"].notna()] = pd.NA  # a failed run counted nothing
            df[c] = counts
        else:
            df[c] = pd.to_numeric(df[c], errors="coerce").astype("Int64")
    return df


def write_table(df: Any, path: str | os.PathLike[str]) -> None:
    """Write ``df`` as Parquet or CSV (by the suffix), replacing ``path`` only once complete."""
    from desmon.paths import replacing

    if str(path).lower().endswith(".parquet"):
        with replacing(path, "wb") as fh:
            df.to_parquet(fh, engine="pyarrow", index=False)
    else:
        with replacing(path) as fh:
            df.to_csv(fh, index=False, lineterminator="\n")


def read_table(path: str | os.PathLike[str], text_columns: tuple[str, ...] = ()) -> Any:
    """A table written by ``desmon sweep`` (Parquet or CSV) as a DataFrame, or a SweepError;
    ``text_columns`` (a text parameter's) read from a CSV as written (``01``, not the
    number 1; ``NA``, not a missing value)."""
    import pandas as pd

    if not str(path).lower().endswith(TABLE_SUFFIXES):
        raise SweepError(f"{path}: not a sweep table: desmon sweep writes .parquet or .csv files (-o results.parquet)")
    try:
        if str(path).lower().endswith(".parquet"):
            return pd.read_parquet(path)
        df = pd.read_csv(path)
        texts = [c for c in text_columns if c in df.columns]
        if texts:
            raw = pd.read_csv(path, usecols=texts, dtype=str, keep_default_na=False)
            for c in texts:
                df[c] = raw[c]
        return df
    except (OSError, ValueError) as exc:
        raise SweepError(f"{path}: cannot be read as a sweep table ({' '.join(str(exc).split())[:200]})") from None
    except Exception as exc:  # pyarrow's own errors (not a parquet file, a truncated one)
        raise SweepError(f"{path}: cannot be read as a sweep table ({type(exc).__name__}: {' '.join(str(exc).split())[:200]})") from None


# ------------------------------------------------------------------------------ the journal


class Journal:
    """The rows of a sweep so far, one JSON line each after a header naming the sweep.

    Rows are flushed as they arrive, so an interrupted sweep (Ctrl-C, a crash, kill -9)
    keeps every row that finished; ``--resume`` reads them back.
    """

    def __init__(self, path: Path, identity: dict[str, Any], rows: Sequence[dict[str, Any]]) -> None:
        from desmon.paths import replacing

        self.path = path
        with replacing(path) as fh:  # the header and the rows already done, then appended to
            fh.write(json.dumps({"desmon_sweep": FORMAT, **identity}, sort_keys=True) + "\n")
            for r in rows:
                fh.write(json.dumps(r, sort_keys=True) + "\n")
        self._fh: IO[str] | None = open(path, "a", encoding="utf-8")

    def append(self, row: dict[str, Any]) -> None:
        assert self._fh is not None
        try:
            self._fh.write(json.dumps(row, sort_keys=True) + "\n")
            self._fh.flush()
        except OSError as exc:  # (a full disk: the file object's error names no file)
            raise self._unwritable(exc) from None

    def close(self) -> None:
        if self._fh is not None:
            fh, self._fh = self._fh, None
            try:
                fh.close()
            except OSError as exc:
                raise self._unwritable(exc) from None

    def _unwritable(self, exc: OSError) -> SweepError:
        return SweepError(
            f"{self.path}: cannot write the sweep's journal ({exc.strerror or exc}); the rows it holds are kept: "
            "make room, then run the same sweep again with --resume"
        )


def read_journal(path: Path) -> tuple[dict[str, Any], list[dict[str, Any]]]:
    """(header, rows) of a journal; a truncated last line (a crash while writing) is dropped."""
    lines = path.read_text(encoding="utf-8").splitlines()
    try:
        header = json.loads(lines[0]) if lines else {}
    except json.JSONDecodeError:
        header = {}
    if header.get("desmon_sweep") != FORMAT:
        raise SweepError(f"{path}: not a desmon sweep journal; delete it or name another -o")
    rows = []
    for line in lines[1:]:
        try:
            rows.append(json.loads(line))
        except json.JSONDecodeError:
            break
    return header, rows


# ----------------------------------------------------------------------- resume: same sweep?


def _canonical(axis: Axis, value: Any) -> str:
    if axis.kind == "bool":
        return "true" if (value if isinstance(value, bool) else str(value).lower() == "true") else "false"
    if axis.kind == "int":
        return str(int(value))
    if axis.kind == "float":
        return repr(float(value))
    return str(value)


def _same_setting(stored: Any, value: Any) -> bool:
    """A setting read back from a table (None, NaN or "" when unset) against the sweep's."""
    def norm(x: Any) -> Any:
        if x is None or x == "" or (isinstance(x, float) and x != x):
            return None
        try:
            return float(x)
        except (TypeError, ValueError):
            return str(x)

    return bool(norm(stored) == norm(value))


def _point_value(axis: Axis, value: Any) -> str:
    """A stored value as the grid writes it in a point's text: the axis's own text of the
    value it reads as (a decimal column holds ``4.0`` where the sweep was given ``hours=4``,
    a yes/no column ``true`` where it was given ``faults=1``), else its canonical text."""
    text = _canonical(axis, value)
    wanted = axis.typed(text)
    for v in axis.values:
        if axis.typed(v) == wanted:
            return v
    return text


def key_of_row(row: dict[str, Any], axes: Sequence[Axis]) -> tuple[str, int]:
    """The (point text, seed index) of a stored row, in the grid's own text."""
    text = ",".join(f"{a.name}={_point_value(a, row[a.name])}" for a in axes)
    return (text, int(row["seed_index"]))


def _check_identity(where: str, row: dict[str, Any], names: set[str], grid: Grid, identity: dict[str, Any], settings: dict[str, Any]) -> None:
    """A stored row was made with this sweep's parameters, job, deployer, scenario and settings."""
    if any(row.get(c, "") is None for c in ("point", "seed_index", "seed", "job", "deployer", "exit_code", "wall_s")):
        raise SweepError(f"--resume: {where} holds a row cut short (its last column, wall_s, or its job, seed or exit code is "
                         "empty: the file was cut off while written?); delete the incomplete line(s), or name another -o")
    for column in ("seed_index", "seed", "exit_code"):
        value = row.get(column)
        if isinstance(value, bool) or not (isinstance(value, int) or (isinstance(value, float) and value.is_integer())
                                           or (isinstance(value, str) and value.strip().lstrip("-").isdigit())):
            raise SweepError(f"--resume: {where} holds {column} {value!r} in a row, not a whole number: the table was edited; "
                             "name another -o")
    stored = {c for c in row if c in names}
    if stored != names:
        raise SweepError(f"--resume: {where} sweeps other parameters than -p {', '.join(grid.names) or '(none)'}; "
                         "it is not this sweep: name another -o, or resume it with its own options")
    for column in ("job", "deployer"):
        if str(row.get(column)) != str(identity[column]):
            raise SweepError(f"--resume: {where} was made with --{column} {row.get(column)}, not {identity[column]}: "
                             "it is not this sweep; name another -o")
    if identity["job"] != "evaluate":
        _check_scenario(where, row, identity)
    for name, value in settings.items():
        if not _same_setting(row.get(name), value):
            raise SweepError(f"--resume: {where} was made with {name} {row.get(name)}, not {value}: it is not this sweep; "
                             "name another -o")


def _check_scenario(where: str, row: dict[str, Any], identity: dict[str, Any]) -> None:
    """A stored row was made from this sweep's scenario file, as it reads now."""
    if Path(str(row.get("scenario"))).resolve() != Path(str(identity["scenario"])).resolve():
        raise SweepError(f"--resume: {where} sweeps scenario {row.get('scenario')}, not {identity['scenario']}; name another -o")
    if str(row.get("scenario_digest") or "") != identity["scenario_digest"]:
        raise SweepError(
            f"--resume: {where} was made from another version of {identity['scenario']}, of a module beside it that it "
            f"imports, or of the deployer's file (their content has changed since, "
            f"{row.get('scenario_digest') or 'not recorded'} then, {identity['scenario_digest']} now): its rows are of the "
            "old world; sweep again without --resume to another -o"
        )


def _run_of(where: str, row: dict[str, Any], grid: Grid, runs: dict[tuple[str, int], Run]) -> tuple[str, int]:
    """The key of a stored row, checked to be a run of this grid with the seed it derives."""
    try:
        key = key_of_row(row, grid.axes)
    except (TypeError, ValueError):
        raise SweepError(f"--resume: {where} holds a row whose parameters are not of this grid's types; name another -o") from None
    run = runs.get(key)
    if run is None:
        if key[1] >= grid.seeds and any(k[0] == key[0] for k in runs):
            raise SweepError(f"--resume: {where} holds seed index {key[1]} of {key[0] or 'the point'}, more than --seeds "
                             f"{grid.seeds}: give --seeds {key[1] + 1} or more")
        raise SweepError(f"--resume: {where} holds point {key[0]!r}, which is not in this grid: it is not this sweep "
                         "(give every value it had, or name another -o)")
    if int(row["seed"]) != run.seed:
        as_ints = _whole_numbers(grid, run)
        if as_ints is not None and derive_seed(grid.sweep_seed, as_ints, run.seed_index) == int(row["seed"]):
            floats = [a.name for a in grid.axes if a.kind == "float"]
            raise SweepError(
                f"--resume: {where} was made when the values of -p {', '.join(floats)} were whole numbers ({as_ints}); now a "
                f"decimal value among them makes every value a decimal ({run.point.text}), and a point's seeds derive from its "
                "text, so they differ: resume with the whole-number values only (sweep the decimals with another -o)"
            )
        raise SweepError(f"--resume: {where} was made with another --seed, or with its -p options in another order (a point's "
                         "seeds derive from the sweep seed and the point's text): give the sweep's own --seed and -p order, or name another -o")
    return key


def _whole_numbers(grid: Grid, run: Run) -> str | None:
    """``run``'s point text with its whole-valued floats written as ints (as an int axis
    wrote them), or None if it has no such value."""
    out, changed = [], False
    for axis, (name, text) in zip(grid.axes, run.point.values):
        if axis.kind == "float" and float(text).is_integer():
            text, changed = str(int(float(text))), True
        out.append(f"{name}={text}")
    return ",".join(out) if changed else None


def check_same_sweep(
    where: str, rows: Sequence[dict[str, Any]], grid: Grid, identity: dict[str, Any], settings: dict[str, Any]
) -> dict[tuple[str, int], dict[str, Any]]:
    """The stored rows by key, after checking they belong to this sweep: the same scenario,
    job, deployer, settings and sweep seed, and points of this grid (which may have grown).
    Otherwise a one-line SweepError: ``--resume`` never mixes two sweeps in one table."""
    names = set(grid.names)
    runs: dict[tuple[str, int], Run] = {r.key: r for r in grid.runs()}
    out: dict[tuple[str, int], dict[str, Any]] = {}
    for row in rows:
        _check_identity(where, row, names, grid, identity, settings)
        out[_run_of(where, row, grid, runs)] = row
    return out
