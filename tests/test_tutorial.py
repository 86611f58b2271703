"""The executed documents cannot rot: every command in the sh blocks of docs/tutorial.md
and docs/deployers.md runs and exits as it says, every picture the tutorial shows is
produced by those commands (under out/; tests/test_docs_pictures.py compares them with
docs/img), and the code and output deployers.md quotes are the real ones.

The tutorial's commands run once per test process, in the session fixture
``tutorial_run`` (tests/conftest.py): this module's test checks their exit codes, quotes
and pictures, and tests/test_docs_pictures.py compares the same pictures with docs/img
(both tests are in the xdist group ``tutorial``, so ``make test``'s processes run them in
one process and the commands once)."""

import os
import re
import shlex
import shutil
import subprocess
import sys
from pathlib import Path

import pytest
import warm

EXIT = re.compile(r"#\s*exit\s+(\d+)\s*$")
#: The documents whose sh blocks the suite executes.
EXECUTED_DOCS = ("tutorial.md", "deployers.md")


def doc_blocks(root: Path, doc: str) -> list[list[tuple[str, int]]]:
    """(command, expected exit code) of every line of each of ``docs/<doc>``'s sh blocks."""
    text = (root / "docs" / doc).read_text()
    out = []
    for block in re.findall(r"```sh\n(.*?)```", text, flags=re.S):
        cmds = []
        for line in block.splitlines():
            line = line.strip()
            if not line or line.startswith("#"):
                continue
            m = EXIT.search(line)
            code = int(m.group(1)) if m else 0
            cmds.append((line.split("#")[0].strip(), code))
        out.append(cmds)
    return out


def doc_commands(root: Path, doc: str) -> list[tuple[str, int]]:
    """(command, expected exit code) of every line of ``docs/<doc>``'s sh blocks, in order."""
    return [c for block in doc_blocks(root, doc) for c in block]


def tutorial_commands(root: Path) -> list[tuple[str, int]]:
    return doc_commands(root, "tutorial.md")


def test_the_tutorial_has_commands_and_pictures(root):
    cmds = tutorial_commands(root)
    assert len(cmds) >= 12
    pictures = re.findall(r"!\[[^\]]*\]\(img/([^)]+)\)", (root / "docs" / "tutorial.md").read_text())
    produced = " ".join(c for c, _ in cmds)
    assert pictures and all(f"out/{p}" in produced for p in pictures)
    assert cmds[0] == ("mkdir -p out", 0)  # the folder the commands write to exists before they run


#: (command, the exit code the page gives it, its process) of each command run
Ran = list[tuple[str, int, subprocess.CompletedProcess[str]]]


def run_commands(
    root: Path, work: Path, doc: str, *, env: dict[str, str] | None = None, keep_going: bool = False, jobs: int = 1
) -> Ran:
    """Run the commands of ``docs/<doc>`` in ``work`` (a copy of scenarios/ and
    docs/examples/; a page that writes files makes its out/ first, and a command writing
    into docs/img finds no such folder and fails), in ``env`` (default: this process's)
    with this environment's bin first on PATH. Stops after the first command that exits
    otherwise than the page says, unless ``keep_going``.

    With ``jobs`` > 1 each sh block runs in a folder of its own (a fresh copy, with an
    empty out/), ``jobs`` blocks at a time, the page's last blocks first (its longest
    commands come last); the files each block wrote under out/ are then gathered into
    ``work/out``. A block that reads what an earlier block wrote then fails every time,
    never by chance: such commands belong in one block. The commands are returned in
    the page's order; ``keep_going`` False stops a block at its first wrong exit."""
    env = dict(os.environ if env is None else env)
    env["PATH"] = f"{Path(sys.executable).parent}{os.pathsep}{env.get('PATH', '')}"
    blocks = doc_blocks(root, doc)
    if jobs <= 1:
        _copy_inputs(root, work)
        return _run_block([c for b in blocks for c in b], work, env, keep_going)
    from concurrent.futures import ThreadPoolExecutor

    folders = [work / "blocks" / str(i) for i in range(len(blocks))]
    for folder in folders:
        _copy_inputs(root, folder)
        (folder / "out").mkdir()
    with ThreadPoolExecutor(jobs) as pool:
        running = {i: pool.submit(_run_block, blocks[i], folders[i], env, keep_going) for i in reversed(range(len(blocks)))}
        ran = [r for i in range(len(blocks)) for r in running[i].result()]
    (work / "out").mkdir(exist_ok=True)
    for folder in folders:
        for made in sorted((folder / "out").rglob("*")):
            if made.is_file():
                target = work / "out" / made.relative_to(folder / "out")
                assert not target.exists(), f"two sh blocks of docs/{doc} write out/{target.name}"
                target.parent.mkdir(parents=True, exist_ok=True)
                shutil.copy2(made, target)
    return ran


def _copy_inputs(root: Path, work: Path) -> None:
    shutil.copytree(root / "scenarios", work / "scenarios")
    shutil.copytree(root / "docs" / "examples", work / "docs" / "examples")


def _run_block(cmds: list[tuple[str, int]], work: Path, env: dict[str, str], keep_going: bool) -> Ran:
    ran: Ran = []
    for cmd, expected in cmds:
        argv = shlex.split(cmd)
        if argv[0] == "desmon":  # the installed script, in a process of its own (tests/warm.py)
            proc = warm.run(argv[1:], cwd=work, env=env, timeout=600, script=True)
        else:
            if argv[0] == "python":
                argv[0] = sys.executable
            proc = subprocess.run(argv, cwd=work, env=env, capture_output=True, text=True, timeout=600)
        ran.append((cmd, expected, proc))
        if proc.returncode != expected and not keep_going:
            break
    return ran


def exited_as_documented(ran: Ran) -> dict[str, subprocess.CompletedProcess[str]]:
    """Asserts that each command of ``ran`` exited as its page says, in order; each one's process."""
    for cmd, expected, proc in ran:
        assert proc.returncode == expected, f"{cmd}\n--- stdout\n{proc.stdout[-3000:]}\n--- stderr\n{proc.stderr[-3000:]}"
    return {cmd: proc for cmd, _expected, proc in ran}


def run_doc(root: Path, work: Path, doc: str) -> dict[str, subprocess.CompletedProcess[str]]:
    """Run every command of ``docs/<doc>`` in ``work`` (:func:`run_commands`), asserting
    each exit code; returns each command's process."""
    return exited_as_documented(run_commands(root, work, doc))


@pytest.mark.slow
@pytest.mark.xdist_group("tutorial")
def test_every_tutorial_command_runs_as_documented(root, tutorial_run):
    work, commands = tutorial_run
    ran = exited_as_documented(commands)
    assert [c for c, _, _ in commands] == [c for c, _ in tutorial_commands(root)]  # every one of them ran
    text = (root / "docs" / "tutorial.md").read_text()
    from docblocks import check_quote, quotes

    exact = [q for q in quotes(text) if q.command.startswith("desmon analyze")]  # §10 quotes the exact figures
    assert len(exact) == 2
    for q in exact:
        proc = ran[q.command.split("#")[0].strip()]
        check_quote(q, proc.stdout + proc.stderr)
    for picture in re.findall(r"!\[[^\]]*\]\(img/([^)]+)\)", text):
        made = work / "out" / picture
        assert made.exists() and made.stat().st_size > 20_000, picture
        assert made.read_bytes()[:4] == b"\x89PNG"


@pytest.mark.slow
@pytest.mark.xdist_group("tutorial")
def test_the_transient_method_line_docs_analyze_md_quotes_is_the_one_the_tutorial_command_prints(root, tutorial_run):
    """docs/analyze.md quotes the exposure and the Krylov method line (steps, where the
    deviation settled, the error estimate) of the tutorial's ``desmon analyze
    scenarios/coffee_shift.py -p force_sensors=2``: the exposure is what this run prints;
    the steps, where it settled and its estimate lie within the spread the page states
    between processors (the BLAS kernels round by CPU) of the figures it quotes, widened
    by 2 %."""
    _work, commands = tutorial_run
    command = "desmon analyze scenarios/coffee_shift.py -p force_sensors=2"
    (out,) = [proc.stdout for cmd, _code, proc in commands if cmd == command]
    method = re.search(r"\(Krylov exponential \((\d+) steps, settled at (\d+) s\); error estimate ([0-9.e+-]+)\)", out)
    exposure = re.search(r"Per mission \(T = 28,800 s\): ([0-9.]+) s unmonitored", out)
    assert method and exposure, out
    doc = " ".join((root / "docs" / "analyze.md").read_text().split())
    quoted = re.search(
        r'prints ([0-9.]+) s unmonitored beside "Krylov exponential \((\d+) steps, settled at (\d+) s\); error estimate ([0-9.e+-]+)"', doc
    )
    spread = re.search(r"the steps were ([0-9.]+) % apart, where it settled ([0-9.]+) % apart and its estimates ([0-9.]+) % apart", doc)
    assert quoted and spread, "docs/analyze.md no longer quotes the method line and its spread"
    assert exposure.group(1) == quoted.group(1), (exposure.group(0), quoted.group(1))
    for got, want, apart in zip(method.groups(), quoted.groups()[1:], spread.groups()):
        allowed = float(apart) / 100 + 0.02
        assert abs(float(got) / float(want) - 1.0) <= allowed, (method.group(0), want, apart)


def test_deployers_md_quotes_its_example_deployer_verbatim(root):
    """Every python block of docs/deployers.md is a piece of docs/examples/first_fit.py."""
    text = (root / "docs" / "deployers.md").read_text()
    source = (root / "docs" / "examples" / "first_fit.py").read_text()
    blocks = re.findall(r"```python\n(.*?)```", text, flags=re.S)
    assert len(blocks) >= 5
    for block in blocks:
        assert block in source, block[:200]


def test_deployers_md_code_runs_as_written_and_its_deployer_holds(root):
    """The page's python blocks, in order, are a complete module: they import everything
    they use, and the deployer they define is one the checker runs and finds HOLDS."""
    from desmon.deployment.deployer import Deployer
    from desmon.loader import load_scenario
    from desmon.verify import Checker

    text = (root / "docs" / "deployers.md").read_text()
    code = "\n\n".join(re.findall(r"```python\n(.*?)```", text, flags=re.S))
    namespace: dict = {"__name__": "deployers_md"}
    exec(compile(code, "docs/deployers.md", "exec"), namespace)  # a NameError here: a block uses what no block imports
    assert isinstance(namespace["FIRST_FIT"], Deployer)
    r = Checker(load_scenario(root / "scenarios" / "coffee_handover.py"), namespace["FIRST_FIT"]).run()
    assert r.verdict == "HOLDS"


def test_deployers_md_gives_the_deployer_signature_as_the_code_has_it(root):
    import inspect

    from desmon.deployment.deployer import Deployer

    params = inspect.signature(Deployer).parameters.values()
    written = ", ".join(p.name if p.default is inspect.Parameter.empty else f"{p.name}={p.default!r}" for p in params)
    assert f"`Deployer({written})`" in (root / "docs" / "deployers.md").read_text()


def test_deployers_md_tables_every_field_and_method_of_the_platform_state(root):
    """The table of what a reaction sees of a platform names every field of PlatformState
    and of the Platform it carries, and every public method of PlatformState."""
    import dataclasses

    from desmon.model.platform import Platform
    from desmon.model.system import PlatformState

    text = (root / "docs" / "deployers.md").read_text()
    table = text[text.index("### What a reaction sees of a platform"):]
    table = table[: table.index("\n\n", table.index("| field or method |"))]
    rows = {line.split("|")[1].strip() for line in table.splitlines() if line.startswith("| `")}
    names = {r.strip("`").split("(")[0] for r in rows}
    fields = {f.name for f in dataclasses.fields(PlatformState) if f.init}
    methods = {n for n, v in vars(PlatformState).items() if not n.startswith("_") and (callable(v) or isinstance(v, property))}
    assert fields | methods == names
    platform_row = next(line for line in table.splitlines() if line.startswith("| `platform` |"))
    assert [f.name for f in dataclasses.fields(Platform) if f"`{f.name}`" not in platform_row] == []


@pytest.mark.slow
def test_every_deployers_md_command_runs_and_prints_what_it_quotes(root, tmp_path):
    """The walk-through runs as written (exit codes included), and each text block it
    quotes is output of the commands: the counterexample, the engine line, the refusal."""
    ran = run_doc(root, tmp_path / "byo", "deployers.md")
    assert len(ran) >= 8
    check_quotes(root, "deployers.md", ran, at_least=3)


def check_quotes(root: Path, doc: str, ran: dict[str, subprocess.CompletedProcess[str]], at_least: int) -> None:
    """Each output block of ``docs/<doc>`` is its command's output: exact, or an excerpt
    marked as one (tests/docblocks.py has the rule)."""
    from docblocks import bare_blocks, check_quote, quotes

    text = (root / "docs" / doc).read_text()
    assert bare_blocks(text) == [], "a block without a language: say sh, python or text"
    quoted = quotes(text)
    assert len(quoted) >= at_least
    for q in quoted:
        proc = ran[q.command.split("#")[0].strip()]
        check_quote(q, proc.stdout + proc.stderr)
