"""Every code block of the docs imports what it uses and runs as written, and the output
blocks of docs/detectors.md are what their commands print.

docs/scenarios.md and docs/deployers.md quote their example files piece by piece; their
blocks run as one module in tests/test_scenarios_doc.py and tests/test_tutorial.py."""

from __future__ import annotations

import contextlib
import io
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

from docblocks import blocks
from test_tutorial import check_quotes, run_doc

#: pages whose python blocks each run alone, as written
STANDALONE = ("README.md", "docs/tutorial.md", "docs/detectors.md", "docs/fleet.md", "docs/design.md")


def python_blocks(root: Path, page: str) -> list[str]:
    return [b.body for b in blocks((root / page).read_text()) if b.lang == "python"]


@pytest.mark.parametrize("page", STANDALONE)
def test_every_python_block_runs_as_written(root, page, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "scenarios").symlink_to(root / "scenarios")  # the docs' paths are the repository's, as a reader runs them
    for code in python_blocks(root, page):
        with contextlib.redirect_stdout(io.StringIO()):
            exec(compile(code, page, "exec"), {"__name__": "doc_block"})  # a NameError: the block uses what it never imports


def test_the_detectors_pass_ranges_are_what_their_code_prints(root):
    (code,) = python_blocks(root, "docs/detectors.md")
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        exec(compile(code, "docs/detectors.md", "exec"), {"__name__": "doc_block"})
    printed = dict(re.findall(r"(\d+)/60: (\d+-\d+) of 300", out.getvalue()))
    table = (root / "docs" / "detectors.md").read_text()
    heads = re.search(r"^\| paper k/60 \|(.*)\|$", table, re.M).group(1).split("|")
    cells = re.search(r"^\| sim k/300 that pass \|(.*)\|$", table, re.M).group(1).split("|")
    assert {h.strip(): c.strip().replace("–", "-") for h, c in zip(heads, cells)} == printed


@pytest.mark.slow
def test_the_detectors_output_blocks_are_exactly_what_evaluate_prints(root, tmp_path):
    ran = run_doc(root, tmp_path / "detectors", "detectors.md")
    assert len(ran) == 2
    check_quotes(root, "detectors.md", ran, at_least=2)


@pytest.mark.slow
def test_the_sweeps_python_block_reads_the_table_the_sweep_wrote(root, tmp_path, monkeypatch):
    pytest.importorskip("distributed")
    desmon = str(Path(sys.executable).parent / "desmon")
    (tmp_path / "out").mkdir()  # the page's mkdir -p out
    proc = subprocess.run(
        [desmon, "sweep", str(root / "scenarios" / "robot_day.py"), "-p", "hand_memory=256,384", "-p", "hours=0.1",
         "--seeds", "1", "--workers", "1", "-o", "out/results.parquet", "--no-progress"],
        cwd=tmp_path, capture_output=True, text=True, timeout=600, env={**os.environ},
    )
    assert proc.returncode == 0, proc.stderr
    (code,) = python_blocks(root, "docs/sweeps.md")
    monkeypatch.chdir(tmp_path)
    namespace: dict = {"__name__": "doc_block"}
    exec(compile(code, "docs/sweeps.md", "exec"), namespace)
    assert len(namespace["df"]) == 2 and set(namespace["df"]["hand_memory"]) == {256, 384}


@pytest.mark.slow
def test_the_sweeps_cluster_recipe_starts_single_threaded_workers_without_malloc_trimming(root, tmp_path):
    """The worker line of docs/sweeps.md, run as written (HOST and N filled in), starts N
    single-threaded workers whose processes do not carry Dask's MALLOC_TRIM_THRESHOLD_."""
    import shlex
    import socket
    import time

    pytest.importorskip("distributed")
    from distributed import Client

    sh = [c for b in blocks((root / "docs" / "sweeps.md").read_text()) if b.lang == "sh" for c in b.body.splitlines()]
    (line,) = [c.split("   #")[0] for c in sh if " dask worker " in c]
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    address = f"tcp://127.0.0.1:{port}"
    worker_line = line.replace("tcp://HOST:8786", address).replace("--nworkers N", "--nworkers 2") + " --no-dashboard"
    bindir = Path(sys.executable).parent
    env = {**os.environ, "PATH": f"{bindir}{os.pathsep}{os.environ.get('PATH', '')}"}
    env.pop("MALLOC_TRIM_THRESHOLD_", None)
    quiet = {"env": env, "cwd": tmp_path, "stdout": subprocess.DEVNULL, "stderr": subprocess.DEVNULL, "start_new_session": True}
    procs = [subprocess.Popen(["dask", "scheduler", "--host", "127.0.0.1", "--port", str(port), "--no-dashboard"], **quiet)]
    try:
        procs.append(subprocess.Popen(["bash", "-c", worker_line], **quiet))
        with Client(address, timeout="60s", set_as_default=False) as client:
            client.wait_for_workers(2, timeout=120)
            threads = sorted(w["nthreads"] for w in client.scheduler_info()["workers"].values())
            environ = client.run(lambda: (os.environ.get("MALLOC_TRIM_THRESHOLD_"), os.environ.get("OMP_NUM_THREADS")))
        assert threads == [1, 1], worker_line
        assert sorted(environ.values()) == [(None, "1"), (None, "1")], environ
        assert shlex.split(worker_line)[1:3] == ["dask", "worker"]
    finally:
        for p in reversed(procs):
            os.killpg(p.pid, 15)
            p.wait(timeout=60)
        time.sleep(0.5)


#: the pages whose every block says what it is (docs/design.md's module listing is not yet in this form)
TYPED = (
    "README.md", "docs/tutorial.md", "docs/deployers.md", "docs/scenarios.md", "docs/detectors.md", "docs/sweeps.md",
    "docs/fleet.md", "docs/findings.md", "docs/estimate.md",
)


def test_the_counterexamples_findings_quotes_are_what_verify_prints(root, capsys):
    """docs/findings.md quotes the paper's bugs as ``desmon verify`` prints them (excerpts)."""
    import shlex

    from docblocks import check_quote, quotes

    from desmon.cli import main

    found = quotes((root / "docs/findings.md").read_text())
    assert len(found) >= 5
    for q in found:
        argv = shlex.split(q.command.split("#")[0])
        assert argv[0] == "desmon"
        code = main([*(a if not a.startswith("scenarios/") else str(root / a) for a in argv[1:]), "--no-progress"])
        printed = capsys.readouterr()
        assert code == 1, q.command
        check_quote(q, printed.out.replace(str(root) + "/", "") + printed.err)


@pytest.mark.parametrize("page", TYPED)
def test_every_block_says_whether_it_is_a_command_code_or_output_and_cut_output_says_excerpt(root, page):
    from docblocks import bare_blocks, quotes

    text = (root / page).read_text()
    assert bare_blocks(text) == [], f"{page}: a block without a language (sh, python or text)"
    assert {b.lang for b in blocks(text)} <= {"sh", "python", "text"}
    quotes(text)  # each output block follows a command and is marked an excerpt exactly when it is cut
