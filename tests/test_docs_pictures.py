"""The pictures under docs/img are what the tutorial's commands draw now.

``bench/docs_pictures.py`` lists each picture with the commands that draw it (the
tutorial's own); the slow test compares every picture those commands draw with the
committed one, pixel by pixel (``bench.docs_pictures.difference``: the bytes of a PNG also
depend on the zlib that compressed it, so they are not compared). The commands are the
tutorial's, so the slow test takes the pictures of the tutorial's run (the session fixture
``tutorial_run`` of tests/conftest.py, shared with tests/test_tutorial.py in the xdist
group ``tutorial``: the commands run once); ``bench.docs_pictures.draw`` itself, which
``python -m bench.docs_pictures`` runs, is tested on one picture. Rendering is only pinned
to one matplotlib version: a picture committed from another version is skipped with the
reason, not failed. ``python -m bench.docs_pictures`` redraws the pictures that differ.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

from bench import docs_pictures as pictures
from test_tutorial import tutorial_commands


def test_every_picture_of_the_docs_has_the_tutorial_commands_that_draw_it(root):
    committed = {p.name for p in (root / "docs" / "img").glob("*.png")}
    assert set(pictures.PICTURES) == committed
    shown = set()
    for page in [root / "README.md", *sorted((root / "docs").glob("*.md"))]:
        shown |= set(re.findall(r"\]\((?:docs/)?img/([^)]+\.png)\)", page.read_text()))
    assert shown <= committed, "a page shows a picture that is not in docs/img"
    tutorial = tutorial_commands(root)
    for name, cmds in pictures.PICTURES.items():
        for cmd in cmds:
            assert cmd in tutorial, f"{name}: {cmd[0]!r} (exit {cmd[1]}) is not a command of docs/tutorial.md"
        assert f"out/{name}" in cmds[-1][0].split(), f"{name}: its last command does not write out/{name}"


def _png(path: Path, pixels: np.ndarray, level: int) -> Path:
    from PIL import Image

    Image.fromarray(pixels.astype(np.uint8), "RGBA").save(path, compress_level=level)
    return path


def test_the_comparison_is_of_pixels_and_sees_a_small_change(tmp_path):
    rng = np.random.default_rng(0)
    base = rng.integers(0, 256, size=(60, 80, 4))
    a = _png(tmp_path / "a.png", base, 1)
    same = _png(tmp_path / "same.png", base, 9)  # other bytes, the same pixels
    assert a.read_bytes() != same.read_bytes() and pictures.difference(a, same) is None
    rounded = base.copy()
    rounded[10:20, 10:20, :3] = np.clip(rounded[10:20, 10:20, :3] + 1, 0, 255)
    assert pictures.difference(a, _png(tmp_path / "rounded.png", rounded, 6)) is None
    label = base.copy()
    label[30:33, 40:45, :3] = 255 - label[30:33, 40:45, :3]  # a few pixels of text
    why = pictures.difference(a, _png(tmp_path / "label.png", label, 6))
    assert why is not None and why.startswith("15 of 4,800 pixels differ") and "x 40-44, y 30-32" in why
    assert pictures.difference(a, _png(tmp_path / "small.png", base[:59], 6)) == "size 80x60 drawn, 80x59 committed"


def _skip_unless_drawn_with_this_matplotlib(root: Path, names: list[str]) -> None:
    import matplotlib

    versions = {n: pictures.drawn_with(root / "docs" / "img" / n) for n in names}
    other = {n: v for n, v in versions.items() if v != matplotlib.__version__}
    if other:
        pytest.skip(
            f"docs/img was drawn with matplotlib {sorted(set(map(str, other.values())))}, this is {matplotlib.__version__}: "
            "the pixels may differ between versions (python -m bench.docs_pictures redraws them)"
        )


@pytest.mark.slow
@pytest.mark.xdist_group("tutorial")
def test_every_picture_of_docs_img_is_what_its_commands_draw_now(root, request):
    names = list(pictures.PICTURES)
    _skip_unless_drawn_with_this_matplotlib(root, names)
    work, ran = request.getfixturevalue("tutorial_run")  # the tutorial's commands, run as pictures.draw runs them
    exits = {(cmd, expected): proc for cmd, expected, proc in ran}
    for cmd in pictures.commands(names):  # each ran and exited as the tutorial says (pictures.draw's DrawError)
        proc = exits.get(cmd)
        assert proc is not None, f"{cmd[0]}: not a command of docs/tutorial.md"
        assert proc.returncode == cmd[1], f"{cmd[0]}: exit {proc.returncode}, the tutorial says {cmd[1]}: {(proc.stderr or proc.stdout)[-1000:]}"
    stale = {n: pictures.difference(work / "out" / n, root / "docs" / "img" / n) for n in names}
    assert {n: why for n, why in stale.items() if why} == {}, "python -m bench.docs_pictures redraws them"


def test_the_drawing_tool_draws_a_picture_as_committed_and_stops_at_a_wrong_exit(root, tmp_path, monkeypatch):
    """``bench.docs_pictures.draw`` (``python -m bench.docs_pictures``), on the quickest
    picture: it draws what docs/img holds, and a command that exits otherwise than the
    tutorial says is a DrawError."""
    _skip_unless_drawn_with_this_matplotlib(root, ["fig5.png"])
    drawn = pictures.draw(["fig5.png"], tmp_path / "work", root)
    assert drawn == {"fig5.png": tmp_path / "work" / "out" / "fig5.png"}
    assert pictures.difference(drawn["fig5.png"], root / "docs" / "img" / "fig5.png") is None
    (cmd, _code), = pictures.PICTURES["fig5.png"]
    monkeypatch.setitem(pictures.PICTURES, "fig5.png", ((cmd, 1),))
    with pytest.raises(pictures.DrawError, match="exit 0, the tutorial says 1"):
        pictures.draw(["fig5.png"], tmp_path / "again", root)
