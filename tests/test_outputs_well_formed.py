"""Outputs that carry names stay well-formed whatever a name holds: GraphML parses, a DOT
string or a Cypher literal cannot be ended by a name, the explorer's page holds no markup
or invisible character of a name. The model refuses such names (tests/bad_inputs/
model_name_*.py); here they reach the writers directly, past the model's check."""

from __future__ import annotations

import xml.etree.ElementTree as ET
from html.parser import HTMLParser

import networkx as nx
import pytest

from desmon.errors import ModelError
from desmon.model.checks import check_name, visible
from desmon.repository import labels as L
from desmon.repository.export import graph_to_cypher, graph_to_dot
from desmon.repository.store import graph_to_graphml
from desmon.viz.explore import Frame, Reasons, render_page

HOSTILE = ("a\x00b", "pad\u202e_1", "<hostile>x</hostile>&amp;", 'q"uote', "back\\", "o'k`t", "line\nbreak", "x\x1b[31m")


def _graph() -> nx.MultiDiGraph:
    g = nx.MultiDiGraph()
    for i, name in enumerate(HOSTILE):
        g.add_node(f"{L.PLATFORM}:{name}", label=L.PLATFORM, name=name, **{f"attr{name}": name}, order=i)
        g.add_node(f"{L.DEVICE}:{name}", label=L.DEVICE, name=name, kind=name, platform=name)
        g.add_edge(f"{L.PLATFORM}:{name}", f"{L.DEVICE}:{name}", label=L.HAS_DEVICE, note=name, start=1.0)
    return g


def test_every_hostile_name_is_refused_by_the_model_naming_it():
    for name in HOSTILE:
        with pytest.raises(ModelError) as caught:
            check_name("platform", name)
        message = str(caught.value)
        assert repr(name) in message and "letters, digits" in message and "\n" not in message.replace(repr(name), "")


def test_graphml_parses_and_keeps_every_name_visible(tmp_path):
    out = tmp_path / "g.graphml"
    graph_to_graphml(_graph(), str(out))
    ET.parse(out)  # well-formed XML
    back = nx.read_graphml(out)
    names = {d["name"] for _n, d in back.nodes(data=True)}
    assert names == {visible(n) for n in HOSTILE}
    assert "\x00" not in out.read_text(encoding="utf-8")


def _dot_strings(text: str) -> list[str]:
    """The quoted strings of a DOT text, read as Graphviz reads them (a backslash escapes the next character)."""
    strings, i = [], 0
    while (i := text.find('"', i)) >= 0:
        j = i + 1
        while text[j] != '"':
            j += 2 if text[j] == "\\" else 1
        strings.append(text[i + 1 : j])
        i = j + 1
    return strings


def test_dot_strings_end_where_the_writer_ends_them():
    text = graph_to_dot(_graph(), title="t\x00<")
    for line in text.splitlines():
        if "->" in line or "shape=" in line:
            outside = "".join(part for k, part in enumerate(line.split('"')) if k % 2 == 0)
            assert outside.count("[") == outside.count("]") == 1, line
    strings = _dot_strings(text)
    assert any("a\\\\x00b" in s for s in strings)  # a NUL shown as its escape, the backslash escaped
    assert "\x00" not in text and "\u202e" not in text
    assert not any(s.endswith("\\") and not s.endswith("\\\\") for s in strings)


def _cypher_statements_close(text: str) -> None:
    """Every line after the comment is one statement: its strings and names close before its ';'."""
    for line in text.splitlines()[1:]:
        quote, i = "", 0
        while i < len(line):
            ch = line[i]
            if quote == "'" and ch == "\\":
                i += 2
                continue
            if quote == "`" and line.startswith("``", i):
                i += 2
                continue
            if ch in "'`" and quote in ("", ch):
                quote = "" if quote else ch
            i += 1
        assert quote == "" and line.endswith(";"), line


def test_cypher_literals_and_names_close_whatever_they_hold():
    text = graph_to_cypher(_graph())
    _cypher_statements_close(text.replace("\nbreak", "\\nbreak"))  # (a newline inside a Cypher string is legal)
    assert "\x00" not in text and "\u202e" not in text
    assert "\\u0000" in text and "\\u202e" in text
    assert "`attro'k``t`" in text


class _Tags(HTMLParser):
    def __init__(self) -> None:
        super().__init__()
        self.tags: set[str] = set()

    def handle_starttag(self, tag, attrs):  # type: ignore[no-untyped-def]
        self.tags.add(tag)


def test_the_explorer_page_holds_no_markup_or_invisible_character_of_a_name():
    g = _graph()
    name = HOSTILE[2]
    reasons = (Reasons(graph=name, fixed=HOSTILE[0], acceptable=(HOSTILE[1],), scores=(), failures=((name, (f"{name}: no",)),), text=name),)
    frame = Frame(
        key=HOSTILE[0], title=f"step {name}", event=name, time=None, commands=(name,), raised=((name, name),),
        standing=((name, name),), violations=((name, name),), notes=(name,), graph=g, reasons=reasons,
    )
    page = render_page(f"title {name}", [name, HOSTILE[0]], [frame], banner=HOSTILE[1], command=name)
    assert "\x00" not in page and "\u202e" not in page and "\x1b" not in page
    tags = _Tags()
    tags.feed(page)
    assert "hostile" not in tags.tags  # the name's tag is text, not markup
    assert "&lt;hostile&gt;x&lt;/hostile&gt;&amp;amp;" in page
