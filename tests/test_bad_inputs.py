"""The bad-input corpus: every file in tests/bad_inputs/ is one class of bad input.

Each ``tests/bad_inputs/<name>.py`` starts with comment lines ``# key: value``::

    # args: verify {case} --json {tmp}/out.json      the desmon command line (required)
    # exit: 2                                         its exit code (required)
    # expect: fragment of stderr                      case-insensitive; repeatable (all must appear)

and optionally::

    # untouched: {tmp}/out.json    a file the command must leave as it was (or not create); repeatable
    # mkdir: {tmp}/out.json        create this directory before the run; repeatable
    # copy: {data} {tmp}/run.png   copy a file before the run; repeatable
    # subprocess: yes              run ``python -m desmon`` for real (exit code, no traceback) instead of main()
    # lines: 1                     how many lines stderr has (default 1)

Placeholders: ``{case}`` this file, ``{data}`` its sibling ``<name>.data`` (for inputs
that are not Python, e.g. a binary trace), ``{tmp}`` a fresh empty directory (also the
working directory, so default output names land there), ``{root}`` the repository,
``{nl}`` a newline.
Every case also proves stderr holds no traceback.
"""

from __future__ import annotations

import shlex
import shutil
from dataclasses import dataclass, field
from pathlib import Path

import pytest
import warm

from desmon.cli import main

CORPUS = Path(__file__).resolve().parent / "bad_inputs"
ROOT = CORPUS.parent.parent


@dataclass
class Case:
    path: Path
    args: str
    exit: int
    expect: list[str]
    untouched: list[str] = field(default_factory=list)
    mkdir: list[str] = field(default_factory=list)
    copy: list[str] = field(default_factory=list)
    subprocess: bool = False
    lines: int = 1


def parse_case(path: Path) -> Case:
    keys: dict[str, list[str]] = {}
    for line in path.read_text(encoding="utf-8", errors="replace").splitlines():
        if not line.startswith("#"):
            break
        key, sep, value = line[1:].partition(":")
        if sep and key.strip() and " " not in key.strip():
            keys.setdefault(key.strip().lower(), []).append(value.strip())
    missing = [k for k in ("args", "exit", "expect") if k not in keys]
    assert not missing, f"{path.name}: header lacks {', '.join(missing)} (see tests/test_bad_inputs.py)"
    return Case(
        path=path,
        args=keys["args"][0],
        exit=int(keys["exit"][0]),
        expect=keys["expect"],
        untouched=keys.get("untouched", []),
        mkdir=keys.get("mkdir", []),
        copy=keys.get("copy", []),
        subprocess=keys.get("subprocess", ["no"])[0].lower() in ("yes", "true", "1"),
        lines=int(keys.get("lines", ["1"])[0]),
    )


CASES = sorted(CORPUS.glob("*.py"))


def test_the_corpus_covers_every_class_of_bad_input():
    names = {p.stem.split("_")[0] for p in CASES}
    assert {"cli", "plot", "output", "exit"} <= names
    assert len(CASES) >= 30


@pytest.mark.parametrize("path", CASES, ids=[p.stem for p in CASES])
def test_bad_input_ends_in_one_line_with_its_exit_code(path: Path, tmp_path: Path, monkeypatch, capsys):
    case = parse_case(path)
    work = tmp_path / "tmp"
    work.mkdir()
    values = {"case": str(path), "data": str(path.with_suffix(".data")), "tmp": str(work), "root": str(ROOT), "nl": "\n"}

    def fill(token: str) -> str:
        for key, value in values.items():
            token = token.replace("{" + key + "}", value)
        return token

    argv = [fill(token) for token in shlex.split(case.args)]
    for d in case.mkdir:
        Path(fill(d)).mkdir(parents=True)
    for pair in case.copy:
        src, dst = (fill(t) for t in shlex.split(pair))
        shutil.copyfile(src, dst)
    guarded = [Path(fill(u)) for u in case.untouched]
    before = {p: (p.read_bytes() if p.exists() else None) for p in guarded}

    monkeypatch.chdir(work)
    if case.subprocess:
        proc = warm.run(argv, cwd=work, timeout=120)
        code, out, err = proc.returncode, proc.stdout, proc.stderr
    else:
        code = main(argv)
        out, err = capsys.readouterr()

    shown = f"desmon {shlex.join(argv)}\n--- exit {code}\n--- stdout\n{out[-2000:]}\n--- stderr\n{err[-3000:]}"
    assert "Traceback" not in err, shown
    assert code == case.exit, shown
    assert len(err.splitlines()) == case.lines, shown
    for fragment in case.expect:
        assert fill(fragment).lower() in err.lower(), f"missing {fill(fragment)!r}\n{shown}"
    for p, content in before.items():
        now = p.read_bytes() if p.exists() else None
        assert now == content, f"{p} was {'created' if content is None else 'changed'}\n{shown}"
