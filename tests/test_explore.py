"""``desmon explore``: the page's content (fast, no browser) and the page in a real browser.

The browser test drives Debian's headless Chromium through its chromedriver with Selenium
(nothing is downloaded: both come from ``apt-get install chromium chromium-driver``, which
``.ci/run`` does where they are missing). On a machine without them it is skipped with a
reason that the end of the test run prints on one line (tests/conftest.py); with
``DESMON_REQUIRE_BROWSER=1`` (set by ``.ci/run``) a missing browser fails it instead.
``DESMON_EXPLORE_SCREENSHOTS=DIR`` saves a PNG of every step it visits.
"""

from __future__ import annotations

import json
import os
import re
import shutil
from dataclasses import replace
from html import unescape
from html.parser import HTMLParser
from pathlib import Path

import pytest

from desmon.cli import main

BROWSER_SKIP = "browser test not run: "

# Fig. 5a-d, from the paper's Sect. 4.4 narrative (as tests/test_coffee_case_study.py pins them):
# (source, label, target) of every DEPLOYED_ON / DEPLOYMENT_HISTORY edge, and whether the force sensor is attached
TACTILE, FORCE = "Deployment:tactile_slip_detector", "Deployment:force_slip_detector"
HAND, ARM = "Platform:hand_pc", "Platform:arm_pc"
FORCE_SENSOR_EDGE = (ARM, "HAS_DEVICE", "Device:lwr_wrench")
FIG_5 = {
    "t0": (set(), True),
    "t1": ({(TACTILE, "DEPLOYED_ON", HAND)}, True),
    "t2": ({(TACTILE, "DEPLOYMENT_HISTORY", HAND), (FORCE, "DEPLOYED_ON", ARM)}, True),
    "t3": ({(TACTILE, "DEPLOYMENT_HISTORY", HAND), (FORCE, "DEPLOYMENT_HISTORY", ARM)}, False),
}
DEPLOYMENT_LABELS = ("DEPLOYED_ON", "DEPLOYMENT_HISTORY", "EXECUTABLE_ON")


class _Steps(HTMLParser):
    """Per step section (by data-key): its edges (source, label, target, change), node states and text."""

    def __init__(self) -> None:
        super().__init__(convert_charrefs=True)
        self.steps: dict[str, dict] = {}
        self.order: list[str] = []
        self.current: str | None = None
        self.tags: list[tuple[str, str]] = []  # attributes of external references

    def handle_starttag(self, tag, attrs):  # type: ignore[no-untyped-def]
        a = dict(attrs)
        for name in ("src", "href"):
            if name in a:
                self.tags.append((tag, a[name] or ""))
        if tag == "section" and "step" in (a.get("class") or "").split():
            self.current = a["data-key"]
            self.order.append(self.current)
            self.steps[self.current] = {"edges": set(), "drawn": [], "nodes": {}, "text": []}
        elif self.current is not None and tag == "g" and "edge" in (a.get("class") or "").split():
            edge = (a["data-source"], a["data-label"], a["data-target"], a["data-change"])
            self.steps[self.current]["edges"].add(edge)
            self.steps[self.current]["drawn"].append(edge)  # (two edges alike drawn twice)
        elif self.current is not None and tag == "g" and a.get("class") == "node":
            self.steps[self.current]["nodes"][a["data-node"]] = set((a.get("data-state") or "").split())

    def handle_data(self, data):  # type: ignore[no-untyped-def]
        if self.current is not None:
            self.steps[self.current]["text"].append(data)


def parse(page: str) -> _Steps:
    p = _Steps()
    p.feed(page)
    for s in p.steps.values():
        s["text"] = " ".join(" ".join(s["text"]).split())
    return p


def present(step: dict, labels: tuple[str, ...] = DEPLOYMENT_LABELS) -> set[tuple[str, str, str]]:
    return {(s, lab, t) for s, lab, t, change in step["edges"] if lab in labels and change != "removed"}


@pytest.fixture(scope="module")
def coffee(root, tmp_path_factory) -> tuple[Path, str]:
    out = tmp_path_factory.mktemp("explore") / "explore.html"
    assert main(["explore", str(root / "scenarios" / "coffee_handover.py"), "-o", str(out)]) == 0
    return out, out.read_text(encoding="utf-8")


# --------------------------------------------------------------------------- the page, without a browser
def test_the_coffee_page_has_the_four_steps_of_fig_5_with_their_deployment_edges(coffee):
    steps = parse(coffee[1])
    assert steps.order == ["t0", "t1", "t2", "t3"]
    for key, (edges, attached) in FIG_5.items():
        step = steps.steps[key]
        assert present(step) == edges, key
        has = (*FORCE_SENSOR_EDGE, "removed") not in step["edges"] and FORCE_SENSOR_EDGE in present(step, ("HAS_DEVICE",))
        assert has is attached, key
    t3 = steps.steps["t3"]
    assert (*FORCE_SENSOR_EDGE, "removed") in t3["edges"]  # drawn as removed at the step it goes
    assert "failed" in t3["nodes"]["Device:lwr_wrench"]
    assert "error" in t3["nodes"][FORCE]  # its error stands
    assert "stop force_slip_detector on arm_pc: ok" in t3["text"]
    assert "no_acceptable_platforms: force_slip_detector" in t3["text"]
    assert "no_acceptable_platforms" not in steps.steps["t2"]["text"]
    # the Robot's context moves with the action
    contexts = {k: {t for s, lab, t, c in st["edges"] if lab == "IN_CONTEXT" and c != "removed"} for k, st in steps.steps.items()}
    assert contexts == {"t0": {"Context:hold"}, "t1": {"Context:move_base"}, "t2": {"Context:release"}, "t3": {"Context:release"}}
    # every Fig. 5 node kind and edge kind is drawn
    labels = {lab for st in steps.steps.values() for _s, lab, _t, _c in st["edges"]}
    assert {"HAS_DEVICE", "DEPLOYED_ON", "DEPLOYMENT_HISTORY", "RESOLVES", "IN_CONTEXT"} <= labels
    kinds = {n.split(":", 1)[0] for st in steps.steps.values() for n in st["nodes"]}
    assert {"Platform", "Device", "PerceptionGraph", "Deployment", "Context", "Robot"} <= kinds


def test_the_page_shows_the_reasons_desmon_explain_gives_at_each_step(root, coffee):
    # taken from the library at each moment, not re-stated: every line of Validity.explain()
    # and every failure of every platform appears in that step's section
    from desmon.deployment.validity import acceptable_platforms
    from desmon.loader import load_scenario
    from desmon.repository.query import RepositoryQuery
    from desmon.sim.replay import replay

    scenario = load_scenario(root / "scenarios" / "coffee_handover.py")
    steps = parse(coffee[1])
    for i, te in enumerate(scenario.timeline):
        result = replay(replace(scenario, timeline=scenario.timeline[: i + 1]))
        text = steps.steps[te.label]["text"]
        for spec in scenario.model.specs:
            validity = acceptable_platforms(RepositoryQuery(result.repo), spec.graph)
            for line in validity.explain().splitlines():
                assert " ".join(line.split()) in text, (te.label, spec.graph, line)
            for platform, failures in validity.rejected:
                for f in failures:
                    assert " ".join(str(f).removeprefix(f"{platform}: ").split()) in text


#: four action changes at one instant: the same deployment recorded twice, both at t=5 s
AT_ONE_INSTANT = """
from desmon.model import HOLD, MOVE_BASE, RELEASE
from desmon.model.cob3 import LOADS, care_o_bot
from desmon.model.events import ActionChange, LoadChange
from desmon.model.scenario import Scenario, TimedEvent

scenario = Scenario(
    name="one_instant", model=care_o_bot().build(), initial=tuple(LoadChange(p, mb) for p, mb in LOADS.items()),
    timeline=tuple(TimedEvent(5.0, ActionChange(a), f"t{i}") for i, a in enumerate((HOLD, MOVE_BASE, RELEASE, MOVE_BASE, RELEASE))),
)
"""


def test_history_records_alike_are_each_drawn_and_only_the_new_one_marked_new(tmp_path, capsys):
    """Each step draws as many deployment history edges as the repository holds then (show
    --at lists them), however many share a source, target and start time, and marks as
    new exactly those the step added."""
    scenario = tmp_path / "one_instant.py"
    scenario.write_text(AT_ONE_INSTANT)
    out = tmp_path / "page.html"
    assert main(["explore", str(scenario), "-o", str(out)]) == 0
    capsys.readouterr()
    steps = parse(out.read_text(encoding="utf-8")).steps
    before = 0
    for label in ("t0", "t1", "t2", "t3", "t4"):
        assert main(["show", str(scenario), "--at", label, "--format", "json"]) == 0
        history = [e for e in json.loads(capsys.readouterr().out)["edges"] if e["label"] == "DEPLOYMENT_HISTORY"]
        drawn = [e for e in steps[label]["drawn"] if e[1] == "DEPLOYMENT_HISTORY"]
        assert len(drawn) == len(history), label
        assert sum(e[3] == "added" for e in drawn) == len(history) - before, label
        before = len(history)
    assert before >= 3  # one deployment recorded twice at t=5 s


def test_an_edited_counterexample_gets_verifys_replay_verdict_and_a_bad_step_names_the_file(root, tmp_path, capsys):
    """A file whose invariant was renamed to one its run does not break: the page's banner
    is desmon verify --replay's verdict on it, word for word; a failing start the reaction
    does not issue is one line naming the file."""
    migration = str(root / "scenarios" / "shared_platform.py")
    cex = tmp_path / "cex.json"
    assert main(["verify", migration, "--deployer", "paper", "--json", str(cex), "--no-progress"]) == 1
    doc = json.loads(cex.read_text())
    first = doc["counterexamples"][0]
    other = next(n for n in doc["invariants"] if n != first["invariant"])
    first["invariant"] = other
    edited = tmp_path / "edited.json"
    edited.write_text(json.dumps(doc))
    capsys.readouterr()
    main(["verify", migration, "--deployer", "paper", "--replay", str(edited)])
    verdict = next(line for line in capsys.readouterr().out.splitlines() if line.startswith("verdict: ")).removeprefix("verdict: ")
    page = tmp_path / "page.html"
    assert main(["explore", migration, "--from-json", str(edited), "-o", str(page)]) == 0
    banner = unescape(re.search(r'class="banner">([^<]*)<', page.read_text(encoding="utf-8")).group(1))
    assert verdict in banner
    first["invariant"] = json.loads(cex.read_text())["counterexamples"][0]["invariant"]
    first["states"][1]["fail_indices"], first["states"][1]["failed_starts"] = [7], ["a start"]
    edited.write_text(json.dumps(doc))
    capsys.readouterr()
    assert main(["explore", migration, "--from-json", str(edited), "-o", str(page)]) == 2
    [line] = capsys.readouterr().err.strip().splitlines()
    assert line.startswith(f"desmon: error: {edited}: ") and "fail_indices [7]" in line


def test_the_page_is_self_contained(coffee):
    page = coffee[1]
    steps = parse(page)
    assert all(v.startswith(("data:", "#")) for _tag, v in steps.tags), steps.tags
    assert re.findall(r"https?://[^\s\"'<>)]*", page) == ["http://www.w3.org/2000/svg"] * page.count('xmlns="http://www.w3.org/2000/svg"')
    assert "@import" not in page and "<iframe" not in page
    assert set(re.findall(r"url\(([^)]*)\)", page)) <= {f"#arrow-{k}" for k in ("DEPLOYED_ON", "DEPLOYMENT_HISTORY", "EXECUTABLE_ON", "HAS_DEVICE", "RESOLVES", "IN_CONTEXT", "removed")}
    assert page.count("<script>") == 1 and "<script src" not in page
    assert page.count("<svg") == 1 + 4  # the timeline and one graph per step


def test_the_same_input_writes_the_same_bytes_in_any_process(root, tmp_path, coffee):
    import subprocess
    import sys

    again = tmp_path / "again.html"
    assert main(["explore", str(root / "scenarios" / "coffee_handover.py"), "-o", str(again)]) == 0
    assert again.read_bytes() == coffee[0].read_bytes()
    for seed in ("1", "2"):  # another process, another string hash seed: no set order leaks into the page
        out = tmp_path / f"seed{seed}.html"
        subprocess.run(
            [sys.executable, "-m", "desmon", "explore", str(root / "scenarios" / "coffee_handover.py"), "-o", str(out)],
            check=True, capture_output=True, env={**os.environ, "PYTHONHASHSEED": seed},
        )
        assert out.read_bytes() == coffee[0].read_bytes()


def test_a_counterexample_found_by_verify_and_the_same_one_read_from_json(root, tmp_path, capsys):
    migration = str(root / "scenarios" / "migration.py")
    two = ["--invariant", "valid-or-error", "--invariant", "single-instance"]  # (not the 0-step errors-justified)
    assert main(["explore", migration, "--deployer", "paper", "--verify", *two, "--no-progress", "-o", str(tmp_path / "a.html")]) == 0
    assert main(["verify", migration, "--deployer", "paper", *two, "--no-progress", "--json", str(tmp_path / "cex.json")]) == 1
    # the file names its deployer: --deployer may be left out
    assert main(["explore", migration, "--from-json", str(tmp_path / "cex.json"), "-o", str(tmp_path / "b.html")]) == 0
    # both count the counterexample's steps, as its page does (its initial state is no step)
    assert capsys.readouterr().out.count("(1 step; open it in a browser)") == 2
    a, b = ((tmp_path / f"{n}.html").read_text() for n in "ab")
    sa, sb = parse(a), parse(b)
    assert sa.order == sb.order == ["0", "1"]
    for key in sa.order:
        assert sa.steps[key]["edges"] == sb.steps[key]["edges"]
    # the paper's Algorithm 2 starts a second instance and leaves the first on the broken platform
    assert present(sa.steps["1"], ("DEPLOYED_ON",)) == {(FORCE, "DEPLOYED_ON", "Platform:pc1"), (FORCE, "DEPLOYED_ON", "Platform:pc2")}
    assert "VIOLATED after 1 step:" in unescape(a) and "VIOLATED after 1 step:" in unescape(b)
    assert "single-instance VIOLATED" in sa.steps["1"]["text"]


def test_a_counterexample_of_one_invariant_shows_no_other_as_violated_inside_a_reaction(root, tmp_path, capsys):
    """With --invariant errors-justified (not one watched inside reactions), the page had
    watched every invariant after each start and stop (an empty list read as all) and
    shown coverage and errors-current VIOLATED, which verify says hold."""
    fallbacks = str(root / "scenarios" / "fallbacks.py")
    assert main(["verify", fallbacks, "--deployer", "mutant:stale-errors", "--invariant", "coverage", "--no-progress"]) == 0
    assert main(["explore", fallbacks, "--deployer", "mutant:stale-errors", "--verify", "--invariant", "errors-justified",
                 "--no-progress", "-o", str(tmp_path / "a.html")]) == 0
    capsys.readouterr()
    page = unescape((tmp_path / "a.html").read_text())
    assert "errors-justified VIOLATED" in page
    assert "coverage VIOLATED" not in page and "errors-current VIOLATED" not in page


@pytest.mark.parametrize(
    "args, fragment",
    [
        (["scenarios/nope.py"], "no such scenario file"),
        (["scenarios/coffee_handover.py", "-o", "{tmp}/x.png"], "must end in .html"),
        (["scenarios/coffee_handover.py", "-o", "{tmp}/no/such/dir/x.html"], "does not exist"),
        (["scenarios/coffee_handover.py", "-o", "{tmp}/dir.html"], "directory"),
        (["scenarios/fallbacks.py", "-o", "{tmp}/x.html"], "no scripted timeline"),
        (["scenarios/coffee_handover.py", "--verify", "--no-progress", "-o", "{tmp}/x.html"], "no counterexample to explore"),
        # one invariant holding is named as such, not as the deployer's verdict
        (["scenarios/migration.py", "--verify", "--deployer", "paper", "--invariant", "fixed", "--no-progress", "-o", "{tmp}/x.html"],
         "with deployer paper: fixed HOLDS in 189 states, no counterexample to explore"),
        (["scenarios/coffee_handover.py", "--invariant", "coverage", "-o", "{tmp}/x.html"], "also give --verify"),
        (["scenarios/coffee_handover.py", "--counterexample", "2", "-o", "{tmp}/x.html"], "also give --from-json"),
        (["scenarios/coffee_handover.py", "--from-json", "{tmp}/none.json", "-o", "{tmp}/x.html"], "no such counterexample file"),
        (["scenarios/coffee_handover.py", "--verify", "--from-json", "{tmp}/cex.json", "-o", "{tmp}/x.html"], "give one of them"),
    ],
)
def test_bad_input_is_one_line_and_exit_2(root, tmp_path, capsys, monkeypatch, args, fragment):
    monkeypatch.chdir(root)
    (tmp_path / "cex.json").write_text("{}")
    (tmp_path / "dir.html").mkdir()
    code = main(["explore", *(a.replace("{tmp}", str(tmp_path)) for a in args)])
    err = capsys.readouterr().err
    assert code == 2, err
    assert fragment in err
    assert err.count("\n") == 1 and "Traceback" not in err
    assert not (tmp_path / "x.html").exists()


# --------------------------------------------------------------------------- the page in headless Chromium
def _browser() -> tuple[str, str] | str:
    """(chromium, chromedriver), or why the browser test cannot run here."""
    try:
        import selenium  # noqa: F401
    except ImportError:
        return "selenium is not installed (pip install -e '.[test]')"
    chromium = next((p for p in map(shutil.which, ("chromium", "chromium-browser")) if p), None)
    driver = shutil.which("chromedriver")
    if not chromium or not driver:
        return "headless Chromium not found (apt-get install chromium chromium-driver; .ci/run installs them)"
    return chromium, driver


@pytest.fixture(scope="module")
def browser():  # type: ignore[no-untyped-def]
    found = _browser()
    if isinstance(found, str):
        if os.environ.get("DESMON_REQUIRE_BROWSER"):
            pytest.fail(f"DESMON_REQUIRE_BROWSER is set but {found}")
        pytest.skip(BROWSER_SKIP + found)
    chromium, chromedriver = found
    os.environ.setdefault("SE_OFFLINE", "true")  # Selenium Manager must not look for (or fetch) a browser or driver
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service

    options = webdriver.ChromeOptions()
    options.binary_location = chromium
    for arg in ("--headless=new", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage", "--window-size=1400,1000"):
        options.add_argument(arg)
    options.set_capability("goog:loggingPrefs", {"browser": "ALL"})
    driver = webdriver.Chrome(service=Service(chromedriver), options=options)
    driver.set_page_load_timeout(30)
    try:
        yield driver
    finally:
        driver.quit()


def _console_errors(driver) -> list[dict]:  # type: ignore[no-untyped-def]
    return [e for e in driver.get_log("browser") if e.get("level") == "SEVERE"]


VISIBLE_EDGES = """
const shown = Array.from(document.querySelectorAll("section.step")).filter(s => !s.hidden && s.offsetParent !== null);
if (shown.length !== 1) { return null; }
const svg = shown[0].querySelector("svg.repo").getBoundingClientRect();
return {key: shown[0].getAttribute("data-key"), width: svg.width, height: svg.height,
        text: shown[0].innerText,
        edges: Array.from(shown[0].querySelectorAll("g.edge")).map(g =>
          [g.getAttribute("data-source"), g.getAttribute("data-label"), g.getAttribute("data-target"), g.getAttribute("data-change")])};
"""


def _shown(driver, shots: str | None = None) -> dict:  # type: ignore[no-untyped-def]
    view = driver.execute_script(VISIBLE_EDGES)
    assert view is not None, "not exactly one step is shown"
    view["edges"] = {tuple(e) for e in view["edges"]}
    if shots:
        height = driver.execute_script("return document.documentElement.scrollHeight")
        driver.set_window_size(1400, height + 100)
        driver.save_screenshot(str(Path(shots) / f"explore-{view['key']}.png"))
    return view


@pytest.mark.xdist_group("browser")  # one process starts Chromium (the module's browser fixture) for both
def test_the_explorer_in_headless_chromium_steps_through_fig_5(browser, coffee):
    from selenium.webdriver.common.by import By
    from selenium.webdriver.common.keys import Keys

    shots = os.environ.get("DESMON_EXPLORE_SCREENSHOTS")
    browser.get(coffee[0].resolve().as_uri())
    assert browser.execute_script("return document.body.getAttribute('data-current')") == "0"
    assert _console_errors(browser) == []
    button = {name: browser.find_element(By.ID, name) for name in ("first", "prev", "next", "last")}
    assert not button["first"].is_enabled() and not button["prev"].is_enabled()
    seen = []
    for i, key in enumerate(FIG_5):
        view = _shown(browser, shots)
        seen.append(view["key"])
        assert view["key"] == key
        assert view["width"] > 400 and view["height"] > 200  # the graph is drawn
        edges, attached = FIG_5[key]
        assert {(s, lab, t) for s, lab, t, c in view["edges"] if lab in DEPLOYMENT_LABELS and c != "removed"} == edges, key
        assert ((*FORCE_SENSOR_EDGE, "removed") not in view["edges"] and any(e[:3] == FORCE_SENSOR_EDGE for e in view["edges"])) is attached
        assert key in browser.find_element(By.ID, "counter").text
        if key == "t3":
            assert (*FORCE_SENSOR_EDGE, "removed") in view["edges"]
            assert "stop force_slip_detector on arm_pc: ok" in view["text"]
            assert "no_acceptable_platforms: force_slip_detector" in view["text"]
        if i < 3:
            button["next"].click()
    assert seen == ["t0", "t1", "t2", "t3"]
    assert not button["next"].is_enabled() and not button["last"].is_enabled()
    button["prev"].click()
    assert _shown(browser)["key"] == "t2"
    button["first"].click()
    assert _shown(browser)["key"] == "t0"
    button["last"].click()
    assert _shown(browser)["key"] == "t3"
    browser.find_element(By.CSS_SELECTOR, '.tl-col[data-goto="1"]').click()  # the timeline's columns are steps too
    assert _shown(browser)["key"] == "t1"
    browser.find_element(By.TAG_NAME, "body").send_keys(Keys.ARROW_RIGHT)
    assert _shown(browser)["key"] == "t2"
    assert _console_errors(browser) == []


@pytest.mark.xdist_group("browser")  # one process starts Chromium (the module's browser fixture) for both
def test_a_counterexample_page_loads_in_headless_chromium(browser, root, tmp_path, capsys):
    from selenium.webdriver.common.by import By

    out = tmp_path / "cex.html"
    assert main(["explore", str(root / "scenarios" / "shared_platform.py"), "--deployer", "paper", "--verify", "--no-progress", "-o", str(out)]) == 0
    capsys.readouterr()
    browser.get(out.resolve().as_uri())
    assert _console_errors(browser) == []
    assert _shown(browser)["key"] == "0"
    browser.find_element(By.ID, "next").click()
    view = _shown(browser)
    assert view["key"] == "1" and "VIOLATED" in view["text"]
    assert not browser.find_element(By.ID, "next").is_enabled()
    assert _console_errors(browser) == []


@pytest.mark.xdist_group("browser")  # one process starts Chromium (the module's browser fixture) for both
def test_a_link_to_a_step_opens_it_and_a_malformed_one_opens_the_first(browser, coffee):
    """``page.html#t2`` opens step t2; a fragment that is no URI escape (``#100%``) opens
    the first step, with the buttons working, not a page whose script stopped."""
    from selenium.webdriver.common.by import By

    browser.get(coffee[0].resolve().as_uri() + "#t2")
    assert _shown(browser)["key"] == "t2"
    for fragment in ("#100%", "#%E0%A4%A"):
        browser.get("about:blank")
        browser.get(coffee[0].resolve().as_uri() + fragment)
        assert _shown(browser)["key"] == "t0"
        browser.find_element(By.ID, "next").click()
        assert _shown(browser)["key"] == "t1"
    assert _console_errors(browser) == []


def test_the_banner_says_where_in_the_reaction_in_verifys_words_and_counts_steps_in_english(root, tmp_path, capsys):
    fallbacks = str(root / "scenarios" / "fallbacks.py")
    assert main(["explore", fallbacks, "--deployer", "mutant:stale-errors", "--verify", "--invariant", "errors-justified",
                 "--no-progress", "-o", str(tmp_path / "a.html")]) == 0
    migration = str(root / "scenarios" / "shared_platform.py")
    assert main(["verify", migration, "--deployer", "paper", "--no-progress", "--json", str(tmp_path / "cex.json")]) == 1
    assert main(["explore", migration, "--from-json", str(tmp_path / "cex.json"), "-o", str(tmp_path / "b.html")]) == 0
    capsys.readouterr()
    assert "errors-justified VIOLATED after 3 steps (by the reaction as a whole)" in unescape((tmp_path / "a.html").read_text())
    b = unescape((tmp_path / "b.html").read_text())
    assert "VIOLATED after 1 step:" in b and "after 1 steps" not in b


def test_a_start_the_control_rules_refused_reads_refused_with_its_reason_as_in_desmon_replay(root):
    """The paper's deployer starts the fixed tactile detector on pc2 after pc2 went down: the
    Control rules refuse it. desmon replay said REFUSED (platform down) and the page FAILED,
    which is what a start failure of the environment or the checker's choice reads as."""
    from desmon.cli.explore import timeline_frames
    from desmon.deployment.deployer import PAPER
    from desmon.loader import load_scenario
    from desmon.model import HOLD, MOVE_BASE
    from desmon.model.events import ActionChange, PlatformDown
    from desmon.model.scenario import TimedEvent
    from desmon.sim.replay import format_replay, replay

    down = replace(load_scenario(str(root / "scenarios" / "migration.py")), timeline=(
        TimedEvent(0.0, ActionChange(HOLD), "t0"), TimedEvent(1.0, PlatformDown("pc2"), "t1"), TimedEvent(2.0, ActionChange(MOVE_BASE), "t2")))
    frames = timeline_frames(down, PAPER)
    said = "start tactile_slip_detector on pc2: REFUSED by the Control rules: platform down"
    assert said in format_replay(replay(down, PAPER)) and said in frames[-1].commands, frames[-1].commands


def test_the_first_reactions_refused_start_and_error_are_in_the_json_and_on_the_page(tmp_path, capsys):
    """A deployer that starts its graph on the last platform unchecked: its first reaction's start
    is refused (pc2 has no pad) and it raises an error. verify --json's step 0 listed neither
    (``refused_starts`` and ``raised_errors`` empty), and the page read FAILED."""
    (tmp_path / "blind.py").write_text(
        "from desmon.deployment.ports import DEPLOYMENT_FAILED, RaiseError, Start\n\n"
        "def blind(q, slots, changed, context_changed):\n"
        "    last = [s.name for s in q.platform_states()][-1]\n"
        "    for slot in slots:\n"
        "        if last not in q.deployed_on(slot[0]) and not (yield Start(slot[0], last)):\n"
        "            yield RaiseError(DEPLOYMENT_FAILED, slot[0], last)\n"
    )
    (tmp_path / "two_pcs.py").write_text(
        "from desmon.model import RobotBuilder\nfrom desmon.model.events import ActionChange\n"
        "from desmon.model.scenario import Scenario, TimedEvent\nfrom desmon.verify.bounds import Bounds\n\n"
        "robot = RobotBuilder('r')\nrobot.platform('pc1', memory=400).device('pad', kind='tactile_pad')\nrobot.platform('pc2', memory=400)\n"
        "with robot.rpsl.perception_graph('tac') as g:\n    g.sensor('pads', reads='tactile_pad')\n    g.processing('thr', inputs=['pads'])\n"
        "robot.depsl.deployment_specification('tac').add_constraint('quantity', 'tactile_pad', 1)\n"
        "robot.rules({'hold': ['tac'], 'grasp': ['tac']})\n"
        "scenario = Scenario(name='two_pcs', model=robot.build(), timeline=(TimedEvent(0.0, ActionChange('hold'), 't0'),),\n"
        "                    checker=Bounds(actions=('hold', 'grasp'), platforms=('pc1',)))\n"
    )
    js, page = tmp_path / "cex.json", tmp_path / "cex.html"
    deployer = f"{tmp_path / 'blind.py'}:blind"
    assert main(["verify", str(tmp_path / "two_pcs.py"), "--deployer", deployer, "--json", str(js), "--no-progress"]) == 1
    step0 = json.loads(js.read_text())["counterexamples"][0]["states"][0]
    assert [r["start"] for r in step0["refused_starts"]] == ["start tac on pc2"] and step0["raised_errors"] == ["deployment_failed: tac on pc2"]
    assert main(["explore", str(tmp_path / "two_pcs.py"), "--deployer", deployer, "--from-json", str(js), "-o", str(page)]) == 0
    capsys.readouterr()
    text = parse(page.read_text(encoding="utf-8")).steps["0"]["text"]
    assert "start tac on pc2: REFUSED by the Control rules: the devices of pc2" in text and "FAILED" not in text, text
