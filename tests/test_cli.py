"""The ``pixelworld`` command line."""

from __future__ import annotations

import io
from pathlib import Path

import pytest
from PIL import Image

from pixelworld_env.cli import main

ID = "PW-ba_self-in-container_from_directly-above-v0"


def run(*argv: str, keys: str = "") -> str:
    out = io.StringIO()
    main(list(argv), out=out, keys=io.StringIO(keys))
    return out.getvalue()


def test_list_shows_every_id() -> None:
    lines = run("list").splitlines()
    assert lines[0].split() == ["id", "kind", "category", "train/test", "datasets"]
    assert len(lines) == 1 + 136 + 45
    row = next(line for line in lines if line.startswith("PW-cl_self-in-container_vs_noncontainer-v0 "))
    assert row.split()[1:] == ["classification", "containment", "50/50", "1"]


def test_show_text_and_png(tmp_path: Path) -> None:
    text = run("show", ID, "--split", "test", "--index", "3")
    assert text.startswith(f"{ID} test scene 3\n")
    assert len(text.strip().splitlines()) == 1 + 18 and text.count("S") == 1
    png = tmp_path / "sheet.png"
    assert "wrote 6 scenes" in run("show", ID, "--png", str(png), "--count", "6")
    assert Image.open(png).size == (4 * (35 * 4 + 4), 2 * (18 * 4 + 4))
    with pytest.raises(SystemExit, match="did you mean PW-ba_self-in-container_from_directly-above-v0"):
        run("show", "PW-ba_self-in-container_from_directly-abov-v0")


def test_generate_names_and_pools() -> None:
    assert "1 dataset(s) ready" in run("generate", "cl_self-in-left-corner_vs_on-hline")


def test_play_from_the_keyboard() -> None:
    out = run("play", "PW-cl_self-in-left-corner_vs_on-hline-v0", "--index", "0", "--episode-seed", "0",
              keys="s\nx\n1\n")
    assert "window:" in out and "DOWN: reward +0.0" in out and "unknown key 'x'" in out
    assert "episode over (signalled) after 2 steps" in out
    assert run("play", ID, keys="q\n").rstrip().endswith("quit")
