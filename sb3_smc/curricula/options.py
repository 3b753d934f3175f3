"""The options of a curriculum run, as one checked record: :class:`RunOptions`.

:func:`~sb3_smc.curricula.trainer.train_curriculum`, :func:`~sb3_smc.curricula.trainer.finished_jobs`,
:func:`~sb3_smc.experiments.runner.run_experiment` and the ``sb3-smc train`` / ``sb3-smc experiment`` commands take
the options as keywords (``seeds=``, ``algo=`` ...) or whole (``options=RunOptions(...)``); they make the record once,
where the run starts (:meth:`RunOptions.of`), and every layer below gets it whole: the run's settings
(:func:`~sb3_smc.curricula.run_directory.run_settings`), the scheduler and each job's spec
(:class:`~sb3_smc.curricula.scheduler.Scheduler`), the reuse of a library
(:meth:`~sb3_smc.curricula.reuse.ReuseLibrary.reuse`) and the executor
(:func:`~sb3_smc.curricula.executors.make_executor`).
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass, fields
from pathlib import Path
from typing import Any

from sb3_smc.core.hyperparameters import ALGORITHMS, MAX_TIMESTEPS, recurrent_policy
from sb3_smc.curricula.format import Curriculum, Node
from sb3_smc.curricula.jobs import DEFAULT_REUSE, DEFAULT_SEEDS, REUSE, JobId, check_curriculum, node_budget, node_spec
from sb3_smc.errors import SMCError, SMCTypeError
from sb3_smc.records import TrainingSpec

__all__ = ["BACKENDS", "DEFAULT_GROUP_SIZE", "LIMITS", "MAX_SEEDS", "MAX_WORKERS", "RunOptions"]

BACKENDS = ("local", "ray")
"""Where jobs run: local processes or Ray tasks."""
DEFAULT_GROUP_SIZE = 5
"""The most seeds of a node trained together in one worker (``group_size``; flat nodes and level-2 nodes whose
children are flat; 1: one job per worker, as before issue 44). docs/benchmarks.md, "Grouped jobs in the curriculum
trainer", has the measurement behind it."""
MAX_SEEDS = 1000
"""The most seeds of a run (``seeds``: seeds ``0 .. seeds-1`` of every node; the paper trains 5)."""
MAX_WORKERS = 1024
"""The most jobs a run trains at once (``workers``: local processes, or Ray tasks in flight)."""
MAX_TRAIN_WORLDS = 100_000
"""The most training worlds a run's targets may be cut to (the split's own size is checked when a task is made)."""
LIMITS = {"seeds": MAX_SEEDS, "workers": MAX_WORKERS, "timesteps": MAX_TIMESTEPS, "group_size": MAX_SEEDS}
"""The largest value of each count of :class:`RunOptions` (a group holds seeds of one node: at most ``MAX_SEEDS``),
and of the ``sb3-smc`` options of those names."""


@dataclass(frozen=True, kw_only=True)
class RunOptions:
    """The options of a curriculum run, checked when the record is made (``ValueError`` naming the first option out of
    range; nothing is done before). ``seeds``, ``timesteps``, ``reuse``, ``algo``, ``rnn`` and ``lean_update`` decide
    the trained SMCs (``run.json`` records them); the others decide where and how the jobs train, never what they train.
    The counts (``seeds``, ``workers``, ``timesteps``, ``group_size``) are positive integers up to their :data:`LIMITS`.

    :param seeds: seeds ``0 .. seeds-1`` of every node (at most :data:`MAX_SEEDS`).
    :param timesteps: replaces every node's own budget (``None``: the node's, else the default; at most
        :data:`~sb3_smc.core.hyperparameters.MAX_TIMESTEPS`).
    :param reuse: how many of a used node's best seeds a node calls: ``"two_best"`` or ``"one_best"``.
    :param algo: replaces every node's learner.
    :param rnn: the recurrent cell of every node (``"lstm"`` or ``"gru"``; recurrent algorithms only).
    :param lean_update: train every SMC with the lean update (``train_smc(..., lean_update=True)``: the same update
        up to float rounding, not bit for bit; every node's learner must be ``RecurrentPPO`` or ``RecurrentTRPO``
        with one LSTM or GRU layer, checked before anything is trained); recorded in ``run.json`` when set.
    :param workers: jobs in parallel (local processes; with Ray, the jobs in flight).
    :param backend: ``"local"`` or ``"ray"``.
    :param ray_address: the Ray cluster (``backend="ray"`` only; default: ``RAY_ADDRESS``).
    :param group_size: the most ready seeds of a node trained together as one unit (flat nodes and level-2 nodes
        whose children are flat; 1: every job alone).
    :param tensorboard: write each job's curves under ``DIR/tensorboard``.
    :param reuse_from: a library whose SMCs the run copies instead of training them where it holds them with the
        very spec the run would train (:mod:`sb3_smc.curricula.reuse`); a string is taken as its path.
    :param train_worlds: the run's targets train on the first ``N`` worlds of their training split (their nodes'
        ``train_worlds``; the lower levels on all of theirs: what a library brings a new concept learned from a few
        examples, docs/few_shot.md); ``None``: every node as its curriculum says.
    """

    seeds: int = DEFAULT_SEEDS
    timesteps: int | None = None
    reuse: str = DEFAULT_REUSE
    algo: str | None = None
    rnn: str | None = None
    lean_update: bool = False
    workers: int = 1
    backend: str = BACKENDS[0]
    ray_address: str | None = None
    group_size: int = DEFAULT_GROUP_SIZE
    tensorboard: bool = True
    reuse_from: Path | None = None
    train_worlds: int | None = None

    def __post_init__(self) -> None:
        for name, limit in {**LIMITS, "train_worlds": MAX_TRAIN_WORLDS}.items():
            value = getattr(self, name)
            if value is None and name in ("timesteps", "train_worlds"):
                continue
            if isinstance(value, bool) or not isinstance(value, int) or value < 1:
                raise SMCError(f"{name} must be a positive integer, got {value!r}")
            if value > limit:
                raise SMCError(f"{name} must be at most {limit:,}, got {value:,}")
        for name, flag in (("lean_update", self.lean_update), ("tensorboard", self.tensorboard)):
            if not isinstance(flag, bool):
                raise SMCTypeError(f"{name} must be True or False, got {flag!r}")
        if self.reuse not in REUSE:
            raise SMCError(f"reuse must be one of {list(REUSE)}, got {self.reuse!r}")
        if self.backend not in BACKENDS:
            raise SMCError(f"backend must be {' or '.join(map(repr, BACKENDS))}, got {self.backend!r}")
        if self.ray_address is not None and self.backend != "ray":
            raise SMCError(f"a Ray address ({self.ray_address!r}) is for backend 'ray', not {self.backend!r}")
        if self.algo is not None and self.algo not in ALGORITHMS:  # built-in: worker processes know no registered one
            raise SMCError(f"algo must be one of {ALGORITHMS}, got {self.algo!r}")
        if self.rnn is not None:
            recurrent_policy(self.rnn)  # a known cell (each node's algorithm is checked with its spec)
        if self.reuse_from is not None and not isinstance(self.reuse_from, Path):
            object.__setattr__(self, "reuse_from", Path(self.reuse_from))

    @classmethod
    def of(cls, options: RunOptions | None, **keywords: Any) -> RunOptions:
        """The options of a call that takes them as keywords or whole: ``options`` where given (then every keyword
        must be left at its default: ``SMCError`` naming those that are not), else the record of ``keywords``."""
        if options is None:
            return cls(**keywords)
        if not isinstance(options, RunOptions):
            raise SMCTypeError(f"options must be a RunOptions, got {type(options).__name__}")
        defaults = {f.name: f.default for f in fields(cls)}
        given = [name for name, value in keywords.items() if value != defaults[name]]
        if given:
            raise SMCError(f"give the run's options either as options= or as keywords, not both: {', '.join(given)} "
                           "given beside options")
        return options

    @property
    def k(self) -> int:
        """How many of a used node's best seeds a job calls (``reuse``)."""
        return REUSE[self.reuse]

    def jobs(self, nodes: Iterable[str]) -> list[JobId]:
        """The jobs of ``nodes``, each node with every seed, in order."""
        return [JobId(node, seed) for node in nodes for seed in range(self.seeds)]

    def budget(self, node: Node) -> int:
        """The steps a job of ``node`` trains (:func:`~sb3_smc.curricula.jobs.node_budget`)."""
        return node_budget(node, self.timesteps)

    def spec(self, node: Node, seed: int, children: tuple[str, ...]) -> TrainingSpec:
        """The spec of job ``(node, seed)`` calling ``children``, with this run's ``timesteps``, ``algo`` and ``rnn``
        (:func:`~sb3_smc.curricula.jobs.node_spec`)."""
        return node_spec(node, seed, children, timesteps=self.timesteps, algo=self.algo, rnn=self.rnn)

    def check(self, curriculum: Curriculum, names: Sequence[str]) -> None:
        """Check every node of ``names`` as this run trains it (:func:`~sb3_smc.curricula.jobs.check_curriculum`),
        before anything is trained."""
        check_curriculum(curriculum, names, timesteps=self.timesteps, algo=self.algo, rnn=self.rnn, reuse=self.reuse,
                         lean_update=self.lean_update)
