"""The paper's pictures of behaviour: Fig. 4-style trajectories and a Fig. 1-style timeline of one episode.

* :func:`trajectory_figure`: test environments as rows, methods as columns; each cell is the scene with the cells
  the self visited over the repeats as a heat overlay (brighter orange = more visits), a green (positive) or red
  (negative) frame for the ground truth of a classification task, and for a bring-about task the cells where the
  self would satisfy the goal marked with blue dots.
* :func:`timeline_figure`: one (by default successful) episode of a hierarchical SMC along its primitive moves: each
  call as a labelled span on its depth's row with its outcome, the SMC's own moves as dots, its signal as a marker.
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
from pixelworld_env.core.kinds import task_kind
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
TRAJECTORY_KEYS = {
    "classification": "orange: cells the self visited (brighter = more episodes); frame: the environment's label "
                      "(green positive, red negative)",
    "goal": "orange: cells the self visited (brighter = more episodes); blue dots: cells where the self reaches the "
            "goal",
}
"""The key under a trajectory figure: classification, or a goal kind (bring-about, bring-about-or-cannot)."""


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
    key = fig.text(0.5, 0.005, TRAJECTORY_KEYS["goal" if task_kind(env.kind).tracks_goal else "classification"],
                   ha="center", va="bottom", fontsize=5.5)
    fit_text(key, fig)
    fig.tight_layout(rect=(0, _share(key, fig), 1, 1))
    return save_figure(fig, Path(path))


TIMELINE_TRIES = 20
"""Test episodes :func:`timeline_figure` tries for a successful one (repeats of the paper's test, in order)."""


def _outcome_name(kind: str, outcome: float) -> str:
    """What a call's outcome value says for a child of ``kind``: its signal's name, or ``cut``."""
    spec = task_kind(kind)
    named = [signal.name for signal in spec.signals if signal.outcome == outcome]
    return named[0] if named else "cut" if outcome == spec.cut_outcome else f"{outcome:+g}"


def _spans(episode: Any) -> list[tuple[int, str, float, float, int]]:
    """``(depth, smc, start, end, decision)`` of every stretch of moves one SMC made: a new span where the SMC at
    that depth changes or a new decision begins (so back-to-back calls of one child stay apart); nested calls of one
    grandchild within one call are one span."""
    spans: list[tuple[int, str, float, float, int]] = []
    open_spans: dict[int, list[Any]] = {}
    for t, ((chain, _), decision) in enumerate(zip(episode.moves, episode.move_decisions, strict=True)):
        for depth in list(open_spans):
            span = open_spans[depth]
            if depth > len(chain) or chain[depth - 1] != span[1] or decision != span[4]:
                spans.append(tuple(open_spans.pop(depth)))  # type: ignore[arg-type]
        for depth, name in enumerate(chain, start=1):
            if depth in open_spans:
                open_spans[depth][3] = t + 1
            else:
                open_spans[depth] = [depth, name, t, t + 1, decision]
    spans += [tuple(span) for span in open_spans.values()]  # type: ignore[misc]
    return sorted(spans, key=lambda span: (span[2], span[0]))


def timeline_figure(smc: SMC, target: str, path: str | Path, *, index: int = 0, seed: int = 0,
                    env_id: str | None = None, success: bool = True) -> Path:
    """Fig. 1 (right): one test episode of ``smc`` on environment ``index`` of ``target``, along its primitive
    moves: each call of a child as a labelled span on its depth's row (a new span for each call, its outcome
    written in it), the SMC's own moves as dots and its final signal as a marker (green: the episode succeeded).

    :param success: show the first successful episode of up to :data:`TIMELINE_TRIES` repeats of the paper's test
        (the title says so, or that none succeeded and which one is shown); ``False``: repeat 0.
    :param env_id: default ``PW-<target>-v0``; another environment's SMC task runs its test start state ``index``.
    """
    plt = pyplot()
    env = make_evaluation_env(smc, env_id or f"PW-{target}-v0")  # the SMC's own settings, test split
    start = None if env.pixelworld else start_seed("test", index)
    for repeat in range(TIMELINE_TRIES if success else 1):
        episode = run_episode(smc, env, index=index, seed=episode_seed(seed, repeat, index), start_seed=start)
        if episode.success:
            break
    env.close()
    kinds: dict[str, str] = {}
    pending = list(smc.children)
    while pending:  # every SMC below this one, by name
        child = pending.pop()
        kinds[child.name] = child.kind
        pending += child.children
    names = sorted(kinds)
    colors = {name: plt.cm.tab10(k % 10) for k, name in enumerate(names)}
    spans = _spans(episode)
    depth = max((span[0] for span in spans), default=1 if smc.children else 0)
    moves = len(episode.moves)
    fig, ax = plt.subplots(figsize=(min(14.0, max(6.0, 0.08 * moves + 2.5)), 1.6 + 0.55 * (depth + 1)))
    own = [t for t, (chain, _) in enumerate(episode.moves) if not chain]
    ax.scatter([t + 0.5 for t in own], [0] * len(own), s=9, color="#555555", zorder=3)
    calls = {call["decision"]: call for call in episode.call_log if call["depth"] == 1}
    spanned = {span[4] for span in spans if span[0] == 1}
    for decision, call in calls.items():  # a call that made no move: a narrow bar where the next move is
        if decision not in spanned:
            x = next((t for t, d in enumerate(episode.move_decisions) if d > decision), moves)
            spans.append((1, call["smc"], x - 0.2, x + 0.2, decision))
    for level, name, left, right, decision in spans:
        ax.barh(level, right - left, left=left, height=0.6, color=colors.get(name, "#bbbbbb"), edgecolor="white",
                linewidth=1.0)
        if level == 1 and decision in calls:  # the call's outcome, written in its span where it fits
            label = _outcome_name(kinds.get(name, smc.kind), calls[decision]["outcome"])
            if (right - left) * fig.get_figwidth() / (moves + 1.5) > 0.06 * len(label):
                ax.text((left + right) / 2, level, label, ha="center", va="center", fontsize=6, clip_on=True)
    if episode.signalled:
        signal = smc.action_names[episode.actions[-1]]
        mark = "#2e7d32" if episode.success else "#c62828"
        ax.scatter([moves + 0.5], [0], s=60, marker="D", color=mark, zorder=4)
        ax.text(moves + 0.5, 0.38, signal, ha="center", va="bottom", fontsize=6, color=mark)
    ax.set_xlim(0, moves + 1.5)
    ax.set_ylim(-0.6, depth + 0.6)
    ax.set_yticks(range(depth + 1), [f"{smc.kind} SMC", *[f"depth {d}" for d in range(1, depth + 1)]], fontsize=7)
    ax.set_xlabel("primitive move", fontsize=7)
    ax.tick_params(axis="x", labelsize=6)
    handles = [plt.Rectangle((0, 0), 1, 1, color=colors[n]) for n in names]
    handles += [plt.Line2D([], [], marker="o", linestyle="", color="#555555", markersize=3),
                plt.Line2D([], [], marker="D", linestyle="", color="#2e7d32", markersize=5)]
    labels = [*names, "a move of the SMC itself", "its signal (red: wrong)"]
    legend = fitted_legend(fig, handles, labels, columns=min(len(labels), 3), fontsize=5, loc="lower center",
                           bbox_to_anchor=(0.5, 0.0), frameon=False)
    bottom = _share(legend, fig, grow=True)
    tried = "" if not success else (f", the first success of {repeat + 1} tries" if episode.success
                                    else f"; no success in {TIMELINE_TRIES} tries, the last shown")
    result = "success" if episode.success else "failure"
    fit_text(fig.suptitle(f"{smc.name}\non {target}, test environment {index}: {moves} moves, "
                          f"{episode.length} decisions, {result}{tried}", fontsize=7), fig)
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
