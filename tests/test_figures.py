"""Every figure the report and the demo write keeps all its text on the canvas (legends, titles, tick and axis labels,
captions), whatever the number of methods and the length of their labels: drawn from small synthetic records with
every method of ``METHOD_REGISTRY`` and from scripted SMCs (the trajectories and the timeline)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest

from sb3_smc.experiments import figures
from sb3_smc.experiments.design import METHOD_REGISTRY, level2_targets
from sb3_smc.experiments.report import write_report
from sb3_smc.smc.policies import ScriptedPolicy
from sb3_smc.smc.smc import SMC
from tests.test_experiments import _synthetic_table

DEMO_TARGET = "cl_self-in-container_vs_noncontainer"
DEMO_METHODS = ["cnn", "base", "curr"]
TOLERANCE = 1.0  # pixels


def clipped_texts(fig: Any) -> list[str]:
    """The texts drawn on ``fig`` whose window extent leaves the canvas, each with its extent and the canvas'."""
    from matplotlib.text import Text

    drawn: list[tuple[str, Any]] = []
    draw = Text.draw

    def record(text: Text, renderer: Any) -> None:
        draw(text, renderer)
        if text.get_visible() and text.get_text().strip():
            drawn.append((text.get_text(), text.get_window_extent(renderer)))

    Text.draw = record  # type: ignore[method-assign]
    try:
        fig.canvas.draw()
    finally:
        Text.draw = draw  # type: ignore[method-assign]
    canvas = fig.bbox
    assert drawn, "nothing was drawn"
    return [f"{text!r}: {np.round(box.extents)} outside {np.round(canvas.extents)}" for text, box in drawn
            if box.x0 < canvas.x0 - TOLERANCE or box.y0 < canvas.y0 - TOLERANCE
            or box.x1 > canvas.x1 + TOLERANCE or box.y1 > canvas.y1 + TOLERANCE]


@pytest.fixture
def clipped(monkeypatch) -> dict[str, list[str]]:
    """File stem -> the clipped texts of each figure ``figures`` saves while the test runs."""
    found: dict[str, list[str]] = {}
    save = figures.save_figure

    def check(fig: Any, path: Path) -> Path:
        found[Path(path).stem] = clipped_texts(fig)
        return save(fig, path)

    monkeypatch.setattr(figures, "save_figure", check)
    return found


def test_the_clip_check_sees_a_legend_wider_than_its_figure():
    plt = figures.pyplot()
    fig, ax = plt.subplots(figsize=(2.0, 2.0))
    ax.bar([0], [1], label=METHOD_REGISTRY["base-gru"].label)
    ax.set_xticks([])
    ax.set_yticks([])
    fig.legend(loc="upper center")
    try:
        [clipped] = clipped_texts(fig)
        assert clipped.startswith(repr(METHOD_REGISTRY["base-gru"].label))
    finally:
        plt.close(fig)


def test_the_reports_bar_figures_keep_their_text_on_the_canvas(tmp_path, clipped):
    """Every method of the registry over targets of both kinds, all categories and the pushable curriculum
    (categories, concepts per kind, pushable), and the demo's three methods on its one target (categories: its legend
    was cut at both edges)."""
    methods = list(METHOD_REGISTRY)
    targets = level2_targets()
    chosen = sorted({targets[0], targets[-1], *targets[::9], *level2_targets("pushable")[:3]})
    _synthetic_table(tmp_path / "all", chosen, methods, lambda t, m: 0.3 + 0.05 * methods.index(m))
    write_report(tmp_path / "all", behaviour=False)
    assert set(clipped) == {"categories", "concepts-classification", "concepts-bring-about", "pushable"}
    assert clipped == dict.fromkeys(clipped, [])
    clipped.clear()
    _synthetic_table(tmp_path / "demo", [DEMO_TARGET], DEMO_METHODS, lambda t, m: 0.5)
    write_report(tmp_path / "demo", behaviour=False)
    assert clipped == {"categories": [], "concepts-classification": []}


@pytest.mark.parametrize("horizontal", [False, True])
@pytest.mark.parametrize("count", [1, 3, len(METHOD_REGISTRY)])
def test_bar_panels_fit_every_number_of_methods_with_their_longest_labels(tmp_path, clipped, horizontal, count):
    """The longest labels first, all marked partial (the longest legend entries there are)."""
    methods = sorted(METHOD_REGISTRY, key=lambda m: -len(METHOD_REGISTRY[m].label))[:count]
    panels = [figures.Panel(title, labels, {m: [60.0] * len(labels) for m in methods},
                            {m: [5.0] * len(labels) for m in methods})
              for title, labels in (("classification", ["containment"]), ("bring-about", ["objects", "all"]))]
    figures.bar_panels(panels, methods, "a caption " * 30, tmp_path / "bars.png", horizontal=horizontal,
                       partial=methods)
    assert clipped == {"bars": []}


def _hierarchical(name: str, children: tuple[str, ...]) -> SMC:
    """A classification SMC that calls each of its bring-about ``children`` (three moves left, then SIG1) once, moves
    right and signals SIG1."""
    kids = [SMC(child, "bring-about", ScriptedPolicy(5, lambda obs, step: 4 if step < 3 else 0)) for child in children]
    calls = [6 + k for k in range(len(kids))]
    return SMC(name, "classification", ScriptedPolicy(6 + len(kids), lambda obs, step: calls[step] if step < len(calls)
                                                      else 3 if step == len(calls) else 1), children=kids)


def test_the_trajectory_and_timeline_figures_keep_their_text_on_the_canvas(tmp_path, clipped):
    """The demo's SMC methods and every SMC method of the registry (trajectories), and a timeline of an SMC with long
    names calling many children (its title was cut)."""
    children = tuple(f"curr-{k}/ba_self-on-something-from-somewhere-far-away@{k}" for k in range(6))
    smc = _hierarchical("curr-moves/cl_self-in-container_vs_noncontainer@4", children)
    for methods in (["base", "curr"], [m for m, method in METHOD_REGISTRY.items() if method.smc]):
        figures.trajectory_figure(dict.fromkeys(methods, smc), DEMO_TARGET, tmp_path / "trajectories.png",
                                  environments=2, repeats=1)
        assert clipped == {"trajectories": []}
    for hierarchical in (smc, _hierarchical("curr", children[:1])):
        figures.timeline_figure(hierarchical, DEMO_TARGET, tmp_path / "timeline.png")
        assert clipped == {"trajectories": [], "timeline": []}


def test_the_timeline_keeps_back_to_back_calls_apart_and_names_their_outcomes() -> None:
    """Two calls of one child in a row are two spans (they were one bar); a grandchild's moves are a span of its
    own inside its caller's; outcomes are named by the child's kind."""
    from types import SimpleNamespace

    from sb3_smc.experiments.figures import _outcome_name, _spans

    a, b = ("a",), ("a", "g")
    episode = SimpleNamespace(moves=[(a, "L"), (a, "L"), (a, "R"), (b, "D"), (b, "D"), ((), "U")],
                              move_decisions=[0, 0, 1, 1, 1, 2])
    assert _spans(episode) == [(1, "a", 0, 2, 0), (1, "a", 2, 5, 1), (2, "g", 3, 5, 1)]
    assert [_outcome_name(kind, v) for kind, v in (("bring-about", 1.0), ("bring-about", 0.0),
                                                   ("classification", -1.0), ("bring-about-or-cannot", -1.0),
                                                   ("bring-about-or-cannot", -0.5))] == \
        ["SIG1", "cut", "SIG0", "CANNOT", "cut"]


def test_the_timeline_shows_a_successful_episode_when_there_is_one(tmp_path, monkeypatch) -> None:
    """The default episode is the first success among the paper's repeats (here the third), and the title says
    which try it was; with none, the title says that too."""
    titles: list[str] = []
    real_fit, real_run = figures.fit_text, figures.run_episode
    monkeypatch.setattr(figures, "fit_text", lambda text, fig: (titles.append(text.get_text()), real_fit(text, fig)))
    seeds: list[int] = []

    def third_succeeds(smc, env, **kwargs):
        episode = real_run(smc, env, **kwargs)
        seeds.append(kwargs["seed"])
        episode.success = len(seeds) == 3
        return episode

    monkeypatch.setattr(figures, "run_episode", third_succeeds)
    figures.timeline_figure(_hierarchical("h", ("left",)), DEMO_TARGET, tmp_path / "timeline.png")
    assert len(seeds) == 3 and "success, the first success of 3 tries" in titles[-1]
    assert seeds == [figures.episode_seed(0, repeat, 0) for repeat in range(3)]
    monkeypatch.setattr(figures, "run_episode", real_run)
    figures.timeline_figure(_hierarchical("h", ("left",)), DEMO_TARGET, tmp_path / "timeline.png")
    assert "failure; no success in 20 tries, the last shown" in titles[-1]


def test_the_trajectory_key_says_only_what_is_drawn(tmp_path, monkeypatch) -> None:
    """A classification target's key has no blue dots (no goal is drawn), a bring-about one's no label frame."""
    keys: list[str] = []
    real = figures.fit_text
    monkeypatch.setattr(figures, "fit_text", lambda text, fig: (keys.append(text.get_text()), real(text, fig)))
    smc = _hierarchical("h", ("left",))
    figures.trajectory_figure({"curr": smc}, DEMO_TARGET, tmp_path / "t.png", environments=1, repeats=1)
    assert "frame" in keys[-1] and "blue dots" not in keys[-1]
    assert "blue dots" in figures.TRAJECTORY_KEYS["goal"] and "frame" not in figures.TRAJECTORY_KEYS["goal"]
