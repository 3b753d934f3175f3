"""The paper's pictures of behaviour: Fig. 4-style trajectories and a Fig. 1-style timeline of one episode.

* :func:`trajectory_figure`: test environments as rows, methods as columns; each cell is the scene with the cells
  the self visited over the repeats as a heat overlay (brighter orange = more visits), a green (positive) or red
  (negative) frame for the ground truth of a classification task, and for a bring-about task the cells where the
  self would satisfy the goal marked with blue dots.
* :func:`timeline_figure`: one episode of a hierarchical SMC: at each primitive move, which SMC (at which depth) or
  the policy itself was acting, and the outcome of every SMC call.
* :func:`bar_panels`: Fig. 5-style grouped bars, one panel per kind or category, an error bar only where there is
  more than one value behind a bar.

Legends, titles and captions are fitted to the figure's width (:func:`fitted_legend`, :func:`fit_text`), so that no
text leaves the canvas whatever the methods and their labels (``tests/test_figures.py``).
"""

from __future__ import annotations

import io
import math
import textwrap
from collections import Counter
from collections.abc import Collection, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, cast

import gymnasium as gym
import numpy as np

from pixelworld_env.atomic import atomic_write  # pixelworld_env registers the PW-* ids on import
from pixelworld_env.core.render import rgb_image
from sb3_smc.experiments.design import METHOD_REGISTRY
from sb3_smc.learning.evaluation import episode_seed, make_evaluation_env, run_episode, start_seed

if TYPE_CHECKING:
    from matplotlib.figure import Figure
    from matplotlib.legend import Legend
    from matplotlib.text import Text

    from pixelworld_env.envs.env import PixelWorldEnv
    from sb3_smc.smc.smc import SMC

__all__ = ["METHOD_COLORS", "METHOD_LABELS", "Panel", "bar_panels", "fit_text", "fitted_legend", "goal_cells", "pyplot",
           "save_figure", "trajectory_figure", "timeline_figure"]

METHOD_COLORS = {name: method.colour for name, method in METHOD_REGISTRY.items()}
METHOD_LABELS = {name: method.label for name, method in METHOD_REGISTRY.items()}
TRAJECTORY_KEY = ("orange: cells the self visited (brighter = more episodes); frame: the environment's label "
                  "(green positive, red negative; classification); blue dots: cells where the self reaches the goal "
                  "(bring-about)")


def pyplot() -> Any:
    """matplotlib.pyplot on the headless Agg backend."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


FIT = 0.98
"""The share of a figure's width that a legend, title or caption may take."""
LEGEND_LABEL_WIDTH = 32
"""Characters per line of a legend label wrapped to fit (:func:`fitted_legend`)."""


def fit_text(text: Text, fig: Figure) -> None:
    """Wrap ``text`` (a title or caption centred on the figure) onto lines short enough for the figure's width."""
    lines = text.get_text().splitlines()
    width = max(map(len, lines), default=0)
    while text.get_window_extent().width > FIT * fig.bbox.width and width > 10:
        width = min(width - 1, int(0.9 * width))
        text.set_text("\n".join(textwrap.fill(line, width) for line in lines))


def fitted_legend(fig: Figure, handles: Sequence[Any], labels: Sequence[str], *, columns: int,
                  **kwargs: Any) -> Legend:
    """A figure legend (``kwargs``: its placement and font) that fits the figure's width: its labels whole in the
    most columns, up to ``columns``, that fit, if at least two do (or one where there is one label); else the labels
    wrapped, in the most columns that fit; where not even one column of wrapped labels fits, the figure is widened to
    the legend."""
    most = min(columns, len(labels))
    wrapped = [textwrap.fill(label, LEGEND_LABEL_WIDTH) for label in labels]
    legend = None
    for texts, ncol in [*((labels, n) for n in range(most, min(2, most) - 1, -1)),
                        *((wrapped, n) for n in range(most, 0, -1))]:
        if legend is not None:
            legend.remove()
        legend = fig.legend(handles, texts, ncol=ncol, **kwargs)
        width = legend.get_window_extent().width
        if width <= FIT * fig.bbox.width:
            return legend
    if legend is None:
        raise ValueError("a legend needs at least one label")
    fig.set_figwidth(width / FIT / fig.dpi)
    return legend


def _share(artist: Any, fig: Figure, *, grow: bool = False) -> float:
    """The share of the figure's height that ``artist`` takes, plus a margin of 0.05 inch; ``grow``: the figure is
    made taller by the artist's height first (the axes keep theirs)."""
    height = artist.get_window_extent().height / fig.dpi
    if grow:
        fig.set_figheight(fig.get_figheight() + height)
    return (height + 0.05) / fig.get_figheight()


def save_figure(fig: Figure, path: Path) -> Path:
    """Write ``fig`` as a PNG atomically and close it."""
    plt = pyplot()
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=120)
    plt.close(fig)
    return atomic_write(path, buffer.getvalue())


def goal_cells(env: PixelWorldEnv, index: int) -> list[tuple[int, int]]:
    """Cells where the self (moved there, nothing else moved) satisfies a bring-about env's concept in scene
    ``index``."""
    scene = env.scenes[index]
    me = next(o for o in scene.objects if o.is_self)
    evaluator = env.concept.self_evaluator(scene.objects, scene.floor_row)
    occupied = {p for o in scene.objects if not o.is_self for p in o.pixels}
    out = []
    for row in range(scene.height):
        for col in range(scene.width):
            moved = me.moved_to((row, col))
            if not (moved.pixels & occupied) and all(0 <= r < scene.height and 0 <= c < scene.width
                                                     for r, c in moved.pixels) and evaluator(moved):
                out.append((row, col))
    return out


def trajectory_figure(smcs: Mapping[str, SMC], target: str, path: str | Path, *, environments: int = 6,
                      repeats: int = 10, seed: int = 0) -> Path:
    """Fig. 4: the visited cells of ``repeats`` test episodes of each SMC (``method -> SMC``) on the first
    ``environments`` test environments of ``target``."""
    plt = pyplot()
    env = cast("PixelWorldEnv", gym.make(f"PW-{target}-v0", split="test").unwrapped)
    count = min(environments, len(env.scenes))
    visits: dict[str, list[Counter]] = {}
    for method, smc in smcs.items():  # the episodes of evaluate(smc, split="test", seed=seed), first environments
        wrapped = make_evaluation_env(smc, f"PW-{target}-v0")
        visits[method] = [Counter(cell for r in range(repeats)
                                  for cell in run_episode(smc, wrapped, index=i, seed=episode_seed(seed, r, i)).cells)
                          for i in range(count)]
    fig, axes = plt.subplots(count, len(smcs), figsize=(2.6 * len(smcs), 1.5 * count), squeeze=False)
    for i in range(count):
        scene = env.scenes[i]
        base = rgb_image(scene.grid(), cell_size=1).astype(float) / 255.0
        label = env.labels[i] if env.labels is not None else None
        goals = goal_cells(env, i) if label is None else []
        for j, method in enumerate(smcs):
            ax = axes[i][j]
            heat = np.zeros(base.shape[:2])
            for (r, c), n in visits[method][i].items():
                heat[r, c] = n
            image = base.copy()
            if heat.max() > 0:
                alpha = 0.25 + 0.75 * heat / heat.max()
                mask = heat > 0
                image[mask] = (1 - alpha[mask, None]) * image[mask] + alpha[mask, None] * np.array([1.0, 0.55, 0.0])
            ax.imshow(image, interpolation="nearest")
            if goals:
                rows, cols = zip(*goals, strict=True)
                ax.scatter(cols, rows, s=2, c="#1f77b4", marker="o")
            elif label is None:  # a goal on other objects (a pushed pixel, say): no cell of the self reaches it
                ax.text(0.5, 0.02, "goal: not a cell of the self", transform=ax.transAxes, fontsize=5,
                        ha="center", va="bottom", color="#1f77b4")
            if label is not None:
                for spine in ax.spines.values():
                    spine.set_edgecolor("#2ca02c" if label else "#d62728")
                    spine.set_linewidth(2.5)
            ax.set_xticks([])
            ax.set_yticks([])
            if i == 0:
                ax.set_title(method, fontsize=8)
            if j == 0:
                ax.set_ylabel(f"env {i}", fontsize=7)
    fit_text(fig.suptitle(f"{target}: visited cells over {repeats} test episodes", fontsize=8), fig)
    key = fig.text(0.5, 0.005, TRAJECTORY_KEY, ha="center", va="bottom", fontsize=5.5)
    fit_text(key, fig)
    fig.tight_layout(rect=(0, _share(key, fig), 1, 1))
    return save_figure(fig, Path(path))


def timeline_figure(smc: SMC, target: str, path: str | Path, *, index: int = 0, seed: int = 0,
                    env_id: str | None = None) -> Path:
    """Fig. 1: one test episode of ``smc`` on environment ``index`` of ``target``: a row per depth (0 = the SMC
    itself), a bar per primitive move coloured by the acting SMC, each call's outcome written at its end.
    ``env_id`` (default ``PW-<target>-v0``) may be another environment's SMC task: its test start state ``index``."""
    plt = pyplot()
    env = make_evaluation_env(smc, env_id or f"PW-{target}-v0")  # the SMC's own settings, test split
    start = None if env.pixelworld else start_seed("test", index)
    episode = run_episode(smc, env, index=index, seed=seed, start_seed=start)
    names = sorted({name for chain, _ in episode.moves for name in chain})
    colors = {name: plt.cm.tab20(k % 20) for k, name in enumerate(names)}
    depth = max((len(chain) for chain, _ in episode.moves), default=0)
    fig, ax = plt.subplots(figsize=(max(5.0, 0.12 * len(episode.moves) + 2), 1.2 + 0.5 * (depth + 1)))
    for t, (chain, move) in enumerate(episode.moves):
        ax.barh(0, 1, left=t, color="#444444" if not chain else "#dddddd", edgecolor="none")
        for level, name in enumerate(chain, start=1):
            ax.barh(level, 1, left=t, color=colors[name], edgecolor="none")
        ax.text(t + 0.5, -0.45, move[0], ha="center", va="center", fontsize=5)
    for call in episode.call_log:  # the outcome of each direct call, written where its moves end
        if call["depth"] != 1:
            continue
        own = [t for t, (d, (chain, _)) in enumerate(zip(episode.move_decisions, episode.moves, strict=True))
               if d == call["decision"] and chain]
        later = [t for t, d in enumerate(episode.move_decisions) if d >= call["decision"]]
        end = own[-1] + 1 if own else (later[0] if later else len(episode.moves))
        outcome = {1: "SIG1", -1: "SIG0", 0: "cut"}[call["outcome"]]
        ax.text(end, 1.45, outcome, fontsize=5, ha="right")
    ax.set_yticks(range(depth + 1), ["policy", *[f"depth {d}" for d in range(1, depth + 1)]], fontsize=7)
    ax.set_xlabel("primitive move", fontsize=7)
    bottom = 0.0
    if names:  # the legend below the axes
        legend = fitted_legend(fig, [plt.Rectangle((0, 0), 1, 1, color=colors[n]) for n in names], names,
                               columns=len(names), fontsize=5, loc="lower center", bbox_to_anchor=(0.5, 0.0),
                               frameon=False)
        bottom = _share(legend, fig, grow=True)
    result = "success" if episode.success else "failure"
    fit_text(fig.suptitle(f"{smc.name}\non {target}, test environment {index}: {len(episode.moves)} moves, "
                          f"{episode.length} decisions, {result}", fontsize=7), fig)
    fig.tight_layout(rect=(0, bottom, 1, 1))
    return save_figure(fig, Path(path))


@dataclass(frozen=True)
class Panel:
    """One panel of grouped bars: ``values[method][i]`` (percent, NaN where not run) for ``labels[i]``, with
    ``errors[method][i]`` (``None``: no error bar, one value behind the bar)."""

    title: str
    labels: Sequence[str]
    values: Mapping[str, Sequence[float]]
    errors: Mapping[str, Sequence[float | None]]


def bar_panels(panels: Sequence[Panel], methods: Sequence[str], title: str, path: Path, *,
               horizontal: bool = False, partial: Collection[str] = ()) -> Path:
    """Grouped bars, one bar per method and label, in one panel per :class:`Panel`: side by side, or stacked with
    horizontal bars (``horizontal``, for long concept names) in heights proportional to their labels; the methods of
    ``partial`` (still being trained) are marked so in the legend."""
    plt = pyplot()
    legend_labels = {m: METHOD_LABELS.get(m, m) + (" (partial)" if m in partial else "") for m in methods}
    width = 0.8 / max(1, len(methods))
    if horizontal:
        heights = [max(1.2, 0.1 * len(methods) * len(p.labels) + 0.5) for p in panels]
        fig, axes = plt.subplots(len(panels), 1, figsize=(8.5, sum(heights) + 1.0), squeeze=False,
                                 gridspec_kw={"height_ratios": heights})
    else:
        labels = sum(len(p.labels) for p in panels)
        fig_width = min(11.0, max(4.0, 1.5 + (0.15 * len(methods) + 0.3) * labels))  # 4 inches for the legend
        fig, axes = plt.subplots(1, len(panels), figsize=(fig_width, 3.8),
                                 squeeze=False, gridspec_kw={"width_ratios": [max(1, len(p.labels)) for p in panels]})
    for ax, panel in zip(axes.flat, panels, strict=True):
        positions = np.arange(len(panel.labels))
        for k, method in enumerate(methods):
            errors = [math.nan if e is None else e for e in panel.errors[method]]
            offsets = positions + (k - (len(methods) - 1) / 2) * width
            if horizontal:
                ax.barh(offsets, panel.values[method], width, xerr=errors, color=METHOD_COLORS.get(method),
                        capsize=1.5, error_kw={"elinewidth": 0.6}, label=legend_labels[method])
            else:
                ax.bar(offsets, panel.values[method], width, yerr=errors, color=METHOD_COLORS.get(method),
                       capsize=2, error_kw={"elinewidth": 0.8}, label=legend_labels[method])
        if horizontal:
            ax.set_yticks(positions, panel.labels, fontsize=6)
            ax.invert_yaxis()
            ax.set_xlim(0, 100)
            ax.set_xlabel("test score (%)", fontsize=7)
        else:
            ax.set_xticks(positions, panel.labels, fontsize=7)
            ax.set_ylim(0, 100)
            ax.set_ylabel("test score (%)", fontsize=7)
        ax.tick_params(labelsize=6)
        ax.set_title(panel.title, fontsize=8)
    handles, names = axes.flat[0].get_legend_handles_labels()
    legend = fitted_legend(fig, handles, names, columns=3, loc="upper center", fontsize=6, frameon=False,
                           bbox_to_anchor=(0.5, 1.0))
    # a caption below: tight_layout keeps room for it there
    fit_text(fig.supxlabel(title, fontsize=8, y=0.005, va="bottom"), fig)
    fig.tight_layout(rect=(0, 0, 1, 1 - _share(legend, fig, grow=True)))
    return save_figure(fig, path)
