"""``pixelworld``: list, show, generate and play the PixelWorld benchmark from the command line."""

from __future__ import annotations

import argparse
import difflib
import os
import sys
import warnings
from collections.abc import Sequence
from pathlib import Path
from typing import TextIO

import numpy as np
from PIL import Image, ImageDraw
from tqdm import tqdm

from pixelworld_env.core.constants import Color
from pixelworld_env.core.render import rgb_image
from pixelworld_env.datasets import catalog
from pixelworld_env.datasets.cache import CacheWarning, cache_dir, load_or_generate
from pixelworld_env.datasets.loading import dataset_spec
from pixelworld_env.envs.env import PixelWorldEnv
from pixelworld_env.envs.registration import make_env, registered_ids
from pixelworld_env.errors import PixelWorldError
from pixelworld_env.validation import check_seed

KEYS = {"w": "UP", "a": "LEFT", "s": "DOWN", "d": "RIGHT", "0": "SIG0", "1": "SIG1", "c": "CANNOT"}


def _resolve(name: str) -> tuple[str, tuple[str, ...]]:
    """An env id (or a bare dataset/pool name) -> (id, member datasets)."""
    ids = registered_ids()
    env_id = name if name.startswith("PW-") else f"PW-{name}-v0"
    if env_id not in ids:
        close = difflib.get_close_matches(env_id, list(ids), n=3)
        hint = f"; did you mean {', '.join(close)}?" if close else "; see `pixelworld list`"
        raise SystemExit(f"pixelworld: unknown environment {name!r}{hint}")
    return env_id, ids[env_id]


def cmd_list(args: argparse.Namespace, out: TextIO) -> None:
    rows = []
    for env_id, members in registered_ids().items():
        infos = [catalog.dataset(m) for m in members]
        cats = sorted({i.category for i in infos})
        train = sum(i.train_size for i in infos)
        test = sum(i.test_size for i in infos)
        rows.append((env_id, infos[0].kind, "/".join(cats), f"{train}/{test}", str(len(members))))
    header = ("id", "kind", "category", "train/test", "datasets")
    widths = [max(len(r[i]) for r in [header, *rows]) for i in range(len(header))]
    for row in [header, *rows]:
        out.write("  ".join(cell.ljust(w) for cell, w in zip(row, widths, strict=True)).rstrip() + "\n")


def _env(args: argparse.Namespace, render_mode: str | None) -> PixelWorldEnv:
    _, members = _resolve(args.id)
    return make_env(members, split=args.split, seed=args.seed, render_mode=render_mode)


def _check_index(args: argparse.Namespace, env: PixelWorldEnv) -> None:
    """``--index``: a scene of the split, else the error saying the valid range."""
    count = len(env.scenes)
    if not 0 <= args.index < count:
        raise PixelWorldError(f"--index {args.index} out of range: the {args.split} split of {args.id} has {count} "
                              f"scenes, 0..{count - 1}")


LABEL_HEIGHT = 12
"""Pixels above each tile of a ``show --png`` sheet for its index and label."""
LABEL_COLORS = {1: (0, 150, 0), 0: (200, 0, 0), None: (60, 60, 60)}


def _sheet(env: PixelWorldEnv, count: int) -> np.ndarray:
    """The first ``count`` scenes as a sheet of tiles, each captioned with its index (and label: positives framed
    green, negatives red)."""
    tiles = [rgb_image(s.grid(), cell_size=4) for s in env.scenes[:count]]
    cols = min(4, count)
    rows = -(-count // cols)
    h, w, _ = tiles[0].shape
    cell_h, cell_w = h + 4 + LABEL_HEIGHT, w + 4
    sheet = Image.new("RGB", (cols * cell_w, rows * cell_h), (255, 255, 255))
    draw = ImageDraw.Draw(sheet)
    for k, tile in enumerate(tiles):
        r, c = divmod(k, cols)
        x, y = c * cell_w, r * cell_h
        label = env.labels[k] if env.labels is not None else None
        caption = f"{k}" if label is None else f"{k}: {'positive' if label else 'negative'}"
        draw.text((x + 2, y), caption, fill=LABEL_COLORS[label])
        if label is not None:
            draw.rectangle((x, y + LABEL_HEIGHT, x + w + 3, y + LABEL_HEIGHT + h + 3), outline=LABEL_COLORS[label],
                           width=2)
        sheet.paste(Image.fromarray(tile), (x + 2, y + LABEL_HEIGHT + 2))
    return np.asarray(sheet)


def cmd_show(args: argparse.Namespace, out: TextIO) -> None:
    if args.count < 1:
        raise SystemExit(f"pixelworld show: --count must be >= 1, got {args.count}")
    env = _env(args, "ansi")
    if args.png:
        path = Path(args.png)
        if path.suffix.lower() != ".png":
            raise SystemExit(f"pixelworld show: --png needs a file name ending in .png, got {args.png!r}")
        path.parent.mkdir(parents=True, exist_ok=True)
        count = min(args.count, len(env.scenes))
        Image.fromarray(_sheet(env, count)).save(path)
        out.write(f"wrote {count} scenes of {args.id} ({args.split}) to {args.png}\n")
        return
    if not args.all:
        _check_index(args, env)
    for index in range(len(env.scenes)) if args.all else [args.index]:
        label = f", label {env.labels[index]}" if env.labels is not None else ""
        out.write(f"{args.id} {args.split} scene {index}{label}\n{env.scenes[index].to_ascii()}\n\n")


def cmd_generate(args: argparse.Namespace, out: TextIO) -> None:
    names = catalog.dataset_names() if args.all else [n for name in args.names for n in _resolve(name)[1]]
    if not names:
        raise SystemExit("pixelworld generate: name datasets or ids, or pass --all")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", CacheWarning)
        for name in (bar := tqdm(names, unit="dataset", file=sys.stderr)):
            bar.set_postfix_str(name[:40])
            load_or_generate(dataset_spec(name), args.seed)
    unwritten = [str(w.message) for w in caught if "could not write" in str(w.message)]
    for warning in caught:
        if not issubclass(warning.category, CacheWarning):
            warnings.warn_explicit(warning.message, warning.category, warning.filename, warning.lineno)
    if unwritten:
        raise SystemExit(f"pixelworld generate: {len(names)} dataset(s) generated but {len(unwritten)} could not be "
                         f"cached in {cache_dir()}: {unwritten[0]}")
    out.write(f"{len(names)} dataset(s) ready (seed {args.seed}) in {cache_dir()}\n")


def cmd_play(args: argparse.Namespace, out: TextIO, keys: TextIO) -> None:
    seed = None if args.episode_seed is None else check_seed(args.episode_seed, "--episode-seed")
    env = _env(args, "ansi")
    if args.index is not None:
        _check_index(args, env)
    _, info = env.reset(seed=seed, options=None if args.index is None else {"index": args.index})
    names = env.action_names
    help_line = "keys: " + ", ".join(f"{k}={v}" for k, v in KEYS.items() if v in names) + ", q=quit"
    legend = ", ".join(f"{c.value}={c.name.lower()}" for c in Color)
    task = "bring it about: move until the concept holds, then SIG1"
    if env.task_kind.label == "label":
        task = f"classify: SIG1 if the concept holds, else SIG0 (label of this scene: {info['label']})"
    elif env.task_kind.label == "possible":
        task += f", or CANNOT where it cannot be (this scene: {'possible' if info['label'] else 'impossible'})"
    out.write(f"{args.id}, scene {info['scene_index']}: {task}\nconcept: {env.concept.text}\n")
    total, step = 0.0, 0
    pending: list[str] = []
    while True:
        if not pending:
            out.write(env.render())
            window = env.world.window()
            out.write(f"window: 3 x 3 around the self ({legend})\n"
                      + "\n".join(" ".join(str(int(v)) for v in row) for row in window) + "\n")
            goal = f", goal holds: {'yes' if env.goal_holds() else 'no'}" if env.labels is None else ""
            out.write(f"step {step}, return {total:+.1f}{goal}. {help_line} (several keys on a line play in order)"
                      "\n> ")
            out.flush()
            line = keys.readline()
            if not line:
                out.write("\nquit\n")
                return
            pending = [ch for ch in line.strip() if not ch.isspace()]
            if not pending:
                continue
        key = pending.pop(0)
        if key == "q":
            out.write("\nquit\n")
            return
        action = KEYS.get(key)
        if action not in names:
            out.write(f"unknown key {key!r}; {help_line}\n")
            pending = []
            continue
        _, reward, terminated, truncated, info = env.step(names.index(action))
        total += reward
        step += 1
        out.write(f"{action}: reward {reward:+.1f}\n")
        if terminated or truncated:
            out.write(env.render())
            result = "success" if info["is_success"] else "failure"
            end = "signalled" if terminated else "time limit"
            out.write(f"episode over ({end}) after {step} steps: return {total:+.1f}, {result}\n")
            return


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="pixelworld", description=__doc__)
    sub = parser.add_subparsers(dest="command", required=True)
    sub.add_parser("list", help="every environment id with kind, category and sizes")

    def env_args(p: argparse.ArgumentParser) -> None:
        p.add_argument("id", help="environment id (PW-...-v0) or dataset / concept-pool name")
        p.add_argument("--split", default="train", choices=["train", "test", "all"])
        p.add_argument("--seed", type=int, default=0, help="dataset generation seed")

    show = sub.add_parser("show", help="print scenes as text or save a PNG sheet")
    env_args(show)
    show.add_argument("--index", type=int, default=0)
    show.add_argument("--all", action="store_true", help="print every scene of the split")
    show.add_argument("--png", help="save a PNG sheet of the first --count scenes to this file")
    show.add_argument("--count", type=int, default=16)
    generate = sub.add_parser("generate", help="generate and cache datasets")
    generate.add_argument("names", nargs="*")
    generate.add_argument("--all", action="store_true")
    generate.add_argument("--seed", type=int, default=0)
    play = sub.add_parser("play", help="play an episode from the keyboard (w/a/s/d, 0/1 signals, q quits)")
    env_args(play)
    play.add_argument("--index", type=int, default=None, help="scene index (default: random)")
    play.add_argument("--episode-seed", type=int, default=None)
    return parser


def main(argv: Sequence[str] | None = None, out: TextIO | None = None, keys: TextIO | None = None) -> None:
    args = build_parser().parse_args(argv)
    out = out or sys.stdout
    try:
        if args.command == "list":
            cmd_list(args, out)
        elif args.command == "show":
            cmd_show(args, out)
        elif args.command == "generate":
            cmd_generate(args, out)
        else:
            cmd_play(args, out, keys or sys.stdin)
    except PixelWorldError as err:  # bad input, said in one line; anything else is a bug: its traceback
        raise SystemExit(f"pixelworld {args.command}: error: {err}") from None
    except KeyboardInterrupt:
        out.write("\ninterrupted\n")
        sys.exit(130)
    except BrokenPipeError:  # e.g. `pixelworld list | head`: stop quietly
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        sys.exit(1)
    except OSError as err:  # a file of the user's (show --png): not allowed, the disk full
        where = f" ({err.filename})" if err.filename else ""
        raise SystemExit(f"pixelworld {args.command}: error: {err.strerror or err}{where}") from None


if __name__ == "__main__":
    main()
