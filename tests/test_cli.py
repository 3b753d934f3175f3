"""The ``pixelworld`` command line."""

from __future__ import annotations

import io
import os
from pathlib import Path

import numpy as np
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
    assert len(lines) == 1 + 136 + 11 + 8 + 45 + 5 + 2  # header, datasets (released, pushable, cannot), pools
    row = next(line for line in lines if line.startswith("PW-cl_self-in-container_vs_noncontainer-v0 "))
    assert row.split()[1:] == ["classification", "containment", "50/50", "1"]


def test_show_text_and_png(tmp_path: Path) -> None:
    text = run("show", ID, "--split", "test", "--index", "3")
    assert text.startswith(f"{ID} test scene 3\n")
    assert len(text.strip().splitlines()) == 1 + 18 and text.count("S") == 1
    png = tmp_path / "sheet.png"
    assert "wrote 6 scenes" in run("show", ID, "--png", str(png), "--count", "6")
    assert Image.open(png).size == (4 * (35 * 4 + 4), 2 * (18 * 4 + 4 + 12))  # 12 pixels of caption per row
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


def test_show_refuses_bad_counts_and_names(tmp_path: Path) -> None:
    for count in ("0", "-3"):
        with pytest.raises(SystemExit, match=f"--count must be >= 1, got {count}"):
            run("show", ID, "--png", str(tmp_path / "x.png"), "--count", count)
    with pytest.raises(SystemExit, match="--png needs a file name ending in .png, got"):
        run("show", ID, "--png", str(tmp_path / "sheet"))
    nested = tmp_path / "new" / "folder" / "sheet.png"
    assert "wrote 2 scenes" in run("show", ID, "--png", str(nested), "--count", "2")
    assert nested.is_file()


def test_png_sheets_caption_each_scene_with_its_label(tmp_path: Path) -> None:
    png = tmp_path / "cl.png"
    run("show", "PW-cl_self-in-left-corner_vs_on-hline-v0", "--png", str(png), "--count", "8")
    from pixelworld_env.envs.registration import make_env

    labels = make_env(["cl_self-in-left-corner_vs_on-hline"]).labels[:8]
    pixels = np.asarray(Image.open(png).convert("RGB"))
    tile_h, tile_w = 18 * 4 + 4 + 12, 35 * 4 + 4
    for k, label in enumerate(labels):
        r, c = divmod(k, 4)
        frame = pixels[r * tile_h + 12, c * tile_w + 1]  # the top edge of the tile's frame
        assert tuple(frame) == ((0, 150, 0) if label else (200, 0, 0)), (k, label, frame)
        caption = pixels[r * tile_h : r * tile_h + 10, c * tile_w : c * tile_w + 60]
        assert (caption != 255).any()  # the index and label are written above the tile


def test_generate_fails_when_nothing_can_be_cached(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    locked = tmp_path / "locked"
    locked.mkdir()
    locked.chmod(0o500)
    monkeypatch.setenv("PIXELWORLD_CACHE", str(locked))
    try:
        if os.access(locked, os.W_OK):  # root ignores permissions: make writing fail another way
            monkeypatch.setattr("pixelworld_env.datasets.cache.atomic_write",
                                lambda *a, **k: (_ for _ in ()).throw(PermissionError(13, "Permission denied")))
        with pytest.raises(SystemExit, match=r"1 dataset\(s\) generated but 1 could not be cached in .*locked"):
            run("generate", "cl_self-in-right-corner_vs_on-hline")
    finally:
        locked.chmod(0o700)


def test_play_reads_every_key_of_a_line_and_explains_the_task() -> None:
    out = run("play", "PW-cl_self-in-left-corner_vs_on-hline-v0", "--index", "0", "--episode-seed", "0",
              keys="ssaa\nq\n")
    assert out.count("DOWN: reward") == 2 and out.count("LEFT: reward") == 2
    assert "concept: " in out and "classify: SIG1 if the concept holds" in out and "0=empty" in out
    ba = run("play", ID, "--index", "0", keys="q\n")
    assert "bring it about" in ba and "goal holds: no" in ba
    bc = run("play", "PW-bc_self-in-container_from_on-floor-v0", "--index", "0", keys="c\n")  # CANNOT, possible
    assert "or CANNOT where it cannot be (this scene: possible)" in bc and "c=CANNOT" in bc and "return -1.0" in bc


def test_play_ctrl_c_is_not_a_traceback() -> None:
    class Interrupt(io.StringIO):
        def readline(self, *args):
            raise KeyboardInterrupt

    out = io.StringIO()
    with pytest.raises(SystemExit) as info:
        main(["play", ID], out=out, keys=Interrupt())
    assert info.value.code == 130 and out.getvalue().endswith("interrupted\n")


def test_the_library_table_keeps_long_cells_short() -> None:
    """A long list of children becomes a count, a PixelWorld env id its dataset, and ``=`` where the name says it."""
    from sb3_smc.cli import CHILDREN_WIDTH, _children_cell, _task_cell

    many = [f"cl_self-in-container_vs_noncontainer@{seed}" for seed in range(4)]
    assert _children_cell(many) == "4 SMCs" and _children_cell(["a@0", "b@1"]) == "a@0,b@1"
    assert _children_cell([]) == "-" and len(many[0]) > CHILDREN_WIDTH and _children_cell(many[:1]) == "1 SMC"
    assert _task_cell("cl_x@3", "PW-cl_x-v0") == "=" and _task_cell("mine", "PW-cl_x-v0") == "cl_x"
    assert _task_cell("walker@0", "MiniGrid-Empty-5x5-v0") == "MiniGrid-Empty-5x5-v0" and _task_cell("a", None) == "-"
