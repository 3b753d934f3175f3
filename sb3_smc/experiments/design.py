"""The paper's experiment design: methods, level-2 targets by category, and the curriculum nodes
that train each target with each method. Torch-free.

Methods (:data:`METHOD_REGISTRY`): ``cnn`` (the passive CNN baseline, classification targets only), ``base`` (a
flat SMC on the target), ``curr`` (the hand-designed smc-curr entries, 1-3 per target), ``canon`` (the canonical
smc-canon entry) and their ``-noprim`` variants (:data:`DEFAULT_METHODS`, the paper's); ``base-gru``, a flat SMC
with the paper's learner (RecurrentTRPO with a GRU) whatever the run's learner, a second flat baseline;
``canon-scaled``, canon with a budget that grows with the SMC actions of each target node; ``curr-moves``, curr
whose target nodes' SMC calls cost the episode their moves (at most 100 moves an episode, as a flat SMC). The fair
comparisons (docs/experiments.md, "Equal budgets and the readings of a call"): ``base-400``, the flat SMC with 400
moves an episode (as many as curr makes, median, on every target probed); the sweep of the one free parameter of each
reading of a call, ``curr-cap10`` / ``-cap25`` / ``-cap50`` / ``-cap100`` (a call one step, cut after 10 / 25 / 50
/ 100 moves; ``-cap100`` is curr's setting, trained again in the sweep's run) and ``curr-moves-100`` / ``-200`` /
``-400`` (calls cost their moves, 100 / 200 / 400 moves an episode; ``-100`` is curr-moves' setting); ``base-x1``,
``base-x4``, ``base-x16`` and ``base-x64``, the flat SMC with 1, 4, 16 and 64 times the budget (equal experience,
:data:`EXPERIENCE_METHODS`); ``curr-lower-x2``, curr whose lower-level nodes (every node below its target nodes)
train with twice the run's budget, under names of their own. Every SMC method's jobs are nodes of curricula
(shipped ones, or a flat method's); :func:`plan` merges them so that a lower-level node shared by several methods
is trained once.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from dataclasses import dataclass

from sb3_smc.core.hyperparameters import recurrent_policy
from sb3_smc.curricula import shipped_curricula
from sb3_smc.curricula.format import Curriculum, CurriculumError, Node, merge
from sb3_smc.curricula.jobs import DEFAULT_REUSE, REUSE
from sb3_smc.errors import SMCError

__all__ = ["CATEGORIES", "DEFAULT_METHODS", "DEFAULT_REPEATS", "EXPERIENCE_METHODS", "METHODS", "METHOD_REGISTRY",
           "PAPER_CATEGORIES", "SMC_METHODS", "SWEEP_METHODS", "SWEEP_TARGETS", "ExperimentMethod", "ExperimentPlan",
           "level2_targets", "plan"]


@dataclass(frozen=True)
class ExperimentMethod:
    """One method of the experiment: what it trains, and how the report shows it."""

    name: str
    """Its name in ``--methods``, ``results.csv`` and the report's columns."""
    label: str
    """Its legend entry in the figures."""
    colour: str
    """Its bars' colour in the figures."""
    curricula: str | None = None
    """The ``method`` of the shipped curricula whose target nodes it trains (``smc-curr``); ``None``: a flat SMC on
    each target (a curriculum ``smc-<name>`` of one node per target), or no SMC."""
    smc: bool = True
    """``False``: the passive CNN baseline (:mod:`sb3_smc.experiments.cnn`), no SMCs."""
    classifies_only: bool = False
    """It has results for classification targets only (none for bring-about targets)."""
    algo: str | None = None
    """A flat method's own learner (its nodes' ``algo``); ``None``: the run's (``--algo``)."""
    rnn: str | None = None
    """A flat method's own recurrent cell (``"gru"``); ``None``: the run's (``--rnn``)."""
    paper: str | None = None
    """The paper's method whose numbers it is compared with, when not its own name (``base-gru``: ``base``, the
    paper's flat SMC)."""
    budget_actions: int | None = None
    """The SMC actions the run's budget is meant for: a target node with more (the nodes it uses x the seeds each
    gives) trains proportionally longer (``canon-scaled``: 8, the median of curr's level-2 nodes, which learn within
    the paper's budget); ``None``: the run's budget for every node."""
    count_primitive_steps: bool = False
    """Its target nodes' calls cost the episode the moves they made, not one step each (``curr-moves``): the
    episode's 100 steps bound the moves as a flat SMC's do."""
    max_steps: int | None = None
    """Its target nodes' episode length (decisions; moves where calls cost their moves); ``None``: the paper's 100."""
    call_step_cap: int | None = None
    """The moves a call of its target nodes may make before it is cut off; ``None``: the default 100."""
    budget_factor: float = 1.0
    """A flat method's factor on the run's budget (``base-x4``: 4, so that flat SMCs get as much experience as a
    curriculum's; see :data:`EXPERIENCE_METHODS`)."""
    lower_budget_factor: float = 1.0
    """A curriculum method's factor on the budget of every lower-level node (each node its target nodes use, directly
    or not; ``curr-lower-x2``: 2). A node's budget is part of what it trains, so the lower nodes are copied as
    :meth:`lower_name` and its target nodes are copies calling them; ``1``: the lower nodes are the shipped ones,
    shared with the other methods."""

    @property
    def flat(self) -> bool:
        """Whether it trains a flat SMC on each target."""
        return self.smc and self.curricula is None

    @property
    def paper_name(self) -> str:
        """The paper's method whose numbers it is compared with."""
        return self.paper or self.name

    @property
    def own_learner(self) -> bool:
        """Whether it fixes its SMCs' learner (the run's ``algo`` / ``rnn`` must then be left unset)."""
        return self.algo is not None or self.rnn is not None

    @property
    def _changes_episodes(self) -> bool:
        """Whether it changes how its target nodes' episodes count calls and moves."""
        return self.count_primitive_steps or self.max_steps is not None or self.call_step_cap is not None

    def _with_episodes(self, node: Node) -> Node:
        """``node`` with this method's ``count_primitive_steps``, ``max_steps`` and ``call_step_cap``."""
        return dataclasses.replace(node, count_primitive_steps=node.count_primitive_steps or self.count_primitive_steps,
                                   max_steps=self.max_steps or node.max_steps,
                                   call_step_cap=self.call_step_cap or node.call_step_cap)

    def lower_name(self, name: str) -> str:
        """The name of lower-level node ``name`` as this method trains it: ``<method>/<node>`` where it changes the
        lower levels' budget (:attr:`lower_budget_factor`), else ``name`` (the shipped node)."""
        return name if self.lower_budget_factor == 1 else f"{self.name}/{name}"

    def budget_scale(self, node: Node) -> float:
        """The factor on the run's budget for target ``node``: its SMC actions over :attr:`budget_actions`, at least
        1 (the two best seeds of each node it uses are its SMC actions)."""
        if self.budget_actions is None:
            return 1.0
        return max(1.0, len(node.uses) * REUSE[DEFAULT_REUSE] / self.budget_actions)

    @property
    def changes_targets(self) -> bool:
        """Whether it trains the target nodes of its curricula with settings of its own (:meth:`targets_of`)."""
        return self.budget_actions is not None or self._changes_episodes or self.lower_budget_factor != 1

    @property
    def change(self) -> str:
        """How it trains otherwise than the run says, in words (``""``: as the run says): the report's line on the
        run and the description of its curricula."""
        changes = ([f"its target nodes' budget x their SMC actions / {self.budget_actions}, at least 1"]
                   if self.budget_actions is not None else [])
        if self.count_primitive_steps:
            changes.append("an SMC call of its target nodes costs the episode's steps the moves it made")
        if self.max_steps is not None:
            changes.append(f"{self.max_steps} steps an episode")
        if self.call_step_cap is not None:
            changes.append(f"a call of its target nodes cut after {self.call_step_cap} moves")
        if self.budget_factor != 1:
            changes.append(f"{self.budget_factor:g} x the budget")
        if self.lower_budget_factor != 1:
            changes.append(f"its lower levels' budget x {self.lower_budget_factor:g}")
        return "; ".join(changes)

    def targets_of(self, curriculum: Curriculum, names: Sequence[str]) -> tuple[Curriculum, list[str]]:
        """``curriculum`` and its target nodes ``names`` as this method trains them: as they are, or (a method that
        :attr:`changes_targets`) with copies of them named ``<method>/<node>`` with their budget scaled and / or
        their calls costing their moves, beside the nodes they use (shared with the other methods), or (a
        :attr:`lower_budget_factor`) calling copies of those (:meth:`lower_name`, one per node however many targets
        use it) with their budget scaled."""
        if not self.changes_targets:
            return curriculum, list(names)
        used = {u for node in curriculum.nodes for u in node.uses}
        if used & set(names):
            raise CurriculumError(f"{curriculum.name}: {sorted(used & set(names))[0]!r} is used by another node: "
                                  f"method {self.name} changes top nodes only")
        lower = [] if self.lower_budget_factor == 1 else [
            dataclasses.replace(node, name=self.lower_name(node.name), uses=tuple(map(self.lower_name, node.uses)),
                                line=None, budget_scale=node.budget_scale * self.lower_budget_factor)
            for node in map(curriculum.node, curriculum.order(names)) if node.name not in names]
        copies = [self._with_episodes(dataclasses.replace(node, name=f"{self.name}/{node.name}", line=None,
                                                          uses=tuple(map(self.lower_name, node.uses)),
                                                          budget_scale=node.budget_scale * self.budget_scale(node)))
                  for node in map(curriculum.node, names)]
        return Curriculum(f"{self.name}/{curriculum.name}", (*curriculum.nodes, *lower, *copies),
                          tuple(c.name for c in copies), method=f"smc-{self.name}",
                          description=f"{curriculum.name}, {self.change}"), \
            [c.name for c in copies]

    def flat_node(self, target: str) -> Node:
        """The node of its flat SMC on ``target``: named as the target for ``base``, ``<method>/<target>`` for any
        other flat method (its own learner, episode length or budget, or base's retrained in a run of its own)."""
        if not self.flat:
            raise SMCError(f"method {self.name!r} trains no flat SMCs")
        if self.name == "base":
            return Node(target, target)
        hyperparameters = {"policy": recurrent_policy(self.rnn, self.algo)} if self.rnn is not None else {}
        return self._with_episodes(Node(f"{self.name}/{target}", target, algo=self.algo,
                                        hyperparameters=hyperparameters, budget_scale=self.budget_factor))


METHOD_REGISTRY: dict[str, ExperimentMethod] = {method.name: method for method in (
    ExperimentMethod("cnn", "cnn (passive CNN)", "#888888", smc=False, classifies_only=True),
    ExperimentMethod("base", "base (flat SMC)", "#4c72b0"),
    ExperimentMethod("curr", "curr (hand-designed curricula)", "#dd8452", curricula="smc-curr"),
    ExperimentMethod("canon", "canon (canonical curriculum)", "#55a868", curricula="smc-canon"),
    ExperimentMethod("curr-noprim", "curr, no primitive moves", "#f2b48a", curricula="smc-curr-noprim"),
    ExperimentMethod("canon-noprim", "canon, no primitive moves", "#a5d6a7", curricula="smc-canon-noprim"),
    ExperimentMethod("base-gru", "base-gru (flat SMC, the paper's learner: RecurrentTRPO + GRU)", "#64b5cd",
                     algo="RecurrentTRPO", rnn="gru", paper="base"),
    ExperimentMethod("canon-scaled", "canon-scaled (canon, budget x SMC actions / 8)", "#2e7d32",
                     curricula="smc-canon", paper="canon", budget_actions=8),
    ExperimentMethod("curr-moves", "curr-moves (curr, a call costs its moves)", "#a0522d", curricula="smc-curr",
                     paper="curr", count_primitive_steps=True),
    ExperimentMethod("base-400", "base-400 (flat SMC, 400 moves an episode)", "#1f3d7a", paper="base",
                     max_steps=400),
    *(ExperimentMethod(f"curr-cap{cap}", f"curr-cap{cap} (curr, a call cut after {cap} moves)", colour,
                       curricula="smc-curr", paper="curr", call_step_cap=cap)
      for cap, colour in ((10, "#fde0c5"), (25, "#f9b97f"), (50, "#e8893f"), (100, "#c0631c"))),
    *(ExperimentMethod(f"curr-moves-{steps}", f"curr-moves-{steps} (curr, calls cost their moves, {steps} an episode)",
                       colour, curricula="smc-curr", paper="curr", count_primitive_steps=True, max_steps=steps)
      for steps, colour in ((100, "#d2a07a"), (200, "#c47a4a"), (400, "#6b3310"))),
    *(ExperimentMethod(f"base-x{factor}", f"base-x{factor} (flat SMC, {factor} x the budget)", colour, paper="base",
                       budget_factor=factor)
      for factor, colour in ((1, "#a9bfe0"), (4, "#7f9fd0"), (16, "#2b4f8c"), (64, "#142a52"))),
    ExperimentMethod("curr-lower-x2", "curr-lower-x2 (curr, 2 x the budget of its lower levels)", "#e07b91",
                     curricula="smc-curr", paper="curr", lower_budget_factor=2),
)}
"""Every method by name, in the order of the report's columns."""
METHODS = tuple(METHOD_REGISTRY)
"""Every method's name (the paper's six, then the checks of the method and the fair comparisons)."""
DEFAULT_METHODS = METHODS[:6]
"""The paper's six methods: ``sb3-smc experiment``'s default ``--methods``."""
SMC_METHODS = tuple(name for name, method in METHOD_REGISTRY.items() if method.smc)
SWEEP_METHODS = ("curr-cap10", "curr-cap25", "curr-cap50", "curr-cap100", "curr-moves-100", "curr-moves-200",
                 "curr-moves-400")
"""The sweep of the one free parameter of each reading of a call: a call one step, cut after 10, 25, 50 or 100 moves;
calls costing their moves, 100, 200 or 400 moves an episode. Run together, so that every setting calls the same
lower-level SMCs; the settings of 100 are curr's and curr-moves', under names of their own so that the sweep's run
reports beside the whole table's."""
SWEEP_TARGETS = (
    "ba_self-in-container_from_between-potential-containers",  # headline; containment
    "ba_self-in-container_from_on-floor",
    "cl_self-in-container_vs_noncontainer",
    "cl_container-on-floor_vs_corner",
    "cl_self-left-of-two-objects-vs-one",  # headline; objcon
    "cl_self-inside-container_vs_rest",
    "cl_self-right-of-container_vs_object",
    "ba_self-left-of-two-objects_from_not-left-on-floor",  # objects: the original flat SMCs 100, curr-moves 5.6
    "ba_self-right-of-two-objects_from_not-right-on-floor",  # and 3.2
    "cl_object-on-floor_vs_not",
    "cl_self-between-two-objects_vs_not-between-on-floor",
    "ba_self-in-target-container_from_nontarget-container",  # search
)
"""The sweep's fixed targets, chosen before its run: both kinds and every category, the two headline targets and the
two where the original flat SMCs scored 100 and curr-moves 5.6 and 3.2."""
EXPERIENCE_METHODS = ("base-x1", "base-x4", "base-x16", "base-x64")
"""The flat SMC with 1, 4, 16 and 64 times the budget, in runs whose records keep every SMC's primitive moves
(``base-x1`` is ``base`` retrained there, so that its moves are recorded too): a curve of the flat SMC's score against
the primitive moves it trained on, to set a curriculum's score against at the curriculum's own experience (its target
SMCs' moves and those of every lower-level SMC it was built on; about 10-25 x base's). 1, 4 and 16 x on
:data:`SWEEP_TARGETS`, 1 and 4 x on every other target, and each next point where the curve must go on
(:mod:`sb3_smc.experiments.extension`)."""
CATEGORIES = ("containment", "objcon", "objects", "search", "pushable")
PAPER_CATEGORIES = CATEGORIES[:4]
"""The categories of the released benchmark (``all``); ``pushable`` is the curriculum sb3-smc designed."""
DEFAULT_REPEATS = 10
"""Test episodes per environment and SMC (the paper's protocol)."""


def level2_targets(category: str = "all") -> list[str]:
    """The higher-level target datasets of one category, or ``all`` the paper's 51 of the released benchmark (34
    classification, 17 bring-about; ``pushable``: the 8 nodes above level 1 of the designed pushable
    curriculum)."""
    from pixelworld_env.datasets import catalog  # pixelworld_env (numba, Gymnasium): on use

    if category != "all" and category not in CATEGORIES:
        raise SMCError(f"category must be one of {(*CATEGORIES, 'all')}, got {category!r}")
    targets = {c.node(t).task for c in shipped_curricula().values() if c.method in ("smc-curr", "smc-canon")
               for t in c.targets}
    wanted = PAPER_CATEGORIES if category == "all" else (category,)
    return sorted(t for t in targets if catalog.dataset(t).category in wanted)


@dataclass(frozen=True)
class ExperimentPlan:
    """What an experiment trains: the merged curriculum, and for every (target, method) the nodes whose seeds are
    that method's candidates (``curr``: one node per hand-designed entry)."""

    targets: tuple[str, ...]
    methods: tuple[str, ...]
    curriculum: Curriculum | None
    nodes: dict[tuple[str, str], tuple[str, ...]]

    @property
    def cnn_skipped(self) -> list[str]:
        """The bring-about targets of a plan with ``cnn``: the CNN classifies only, so it has no row for them."""
        return [t for t in self.targets if "cnn" in self.methods and (t, "cnn") not in self.nodes]

    @property
    def training_targets(self) -> list[str]:
        """The node names to train (their lower-level nodes follow)."""
        return [n for key in sorted(self.nodes) for n in self.nodes[key]]


def plan(targets: Sequence[str], methods: Sequence[str]) -> ExperimentPlan:
    """The curricula and nodes of ``methods`` for ``targets`` (dataset names)."""
    from pixelworld_env.datasets import catalog  # pixelworld_env (numba, Gymnasium): on use

    unknown = [m for m in methods if m not in METHODS]
    if unknown:
        raise SMCError(f"unknown method(s) {unknown}; methods are {list(METHODS)}")
    if not methods:
        raise SMCError(f"no methods: nothing to run; methods are {list(METHODS)}")
    if not targets:
        raise SMCError("no targets: nothing to run")
    for given, what in ((methods, "method"), (targets, "target")):
        twice = sorted({x for x in given if list(given).count(x) > 1})
        if twice:
            raise SMCError(f"{what} {twice[0]!r} is given twice")
    for target in targets:
        catalog.dataset(target)  # UnknownDatasetError with close names
    shipped = shipped_curricula()
    nodes: dict[tuple[str, str], tuple[str, ...]] = {}
    used: list[Curriculum] = []
    chosen_methods = [METHOD_REGISTRY[m] for m in methods]
    for method in (m for m in chosen_methods if m.flat):
        flat_nodes = tuple(method.flat_node(t) for t in targets)
        used.append(Curriculum(f"smc-{method.name}", flat_nodes, tuple(n.name for n in flat_nodes),
                               method=f"smc-{method.name}", description="flat SMCs on the experiment's targets"))
        nodes.update({(t, method.name): (n.name,) for t, n in zip(targets, flat_nodes, strict=True)})
    for method in (m for m in chosen_methods if m.curricula is not None):
        found: dict[str, list[str]] = {t: [] for t in targets}
        for curriculum in shipped.values():
            if curriculum.method != method.curricula:
                continue
            chosen = [n for n in curriculum.targets if curriculum.node(n).task in found]
            if chosen:
                trained, names = method.targets_of(curriculum, chosen)
                used.append(trained)
                for name in names:
                    found[trained.node(name).task].append(name)
        for target, names in found.items():
            if names:
                nodes[(target, method.name)] = tuple(names)
    for method in (m for m in chosen_methods if not m.smc):
        wanted = [t for t in targets if not method.classifies_only or catalog.dataset(t).kind == "classification"]
        nodes.update({(t, method.name): () for t in wanted})
    if not nodes:
        raise SMCError(f"nothing to run: the CNN (method cnn) classifies only, and {', '.join(targets)} "
                       f"{'is a bring-about target' if len(targets) == 1 else 'are bring-about targets'}; add an "
                       "SMC method (base, curr, ...) or a classification target")
    missing = [(t, m) for t in targets for m in methods if METHOD_REGISTRY[m].smc and (t, m) not in nodes]
    if missing:
        raise CurriculumError(f"no shipped curriculum trains {missing[0][0]!r} with method {missing[0][1]!r} "
                              f"({len(missing)} target x method pair(s) missing); the level-2 targets are "
                              "sb3_smc.experiments.level2_targets()")
    return ExperimentPlan(targets=tuple(targets), methods=tuple(methods),
                          curriculum=merge(used) if used else None, nodes=nodes)
