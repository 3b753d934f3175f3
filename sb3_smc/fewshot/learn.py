"""``learn_concept``: a new concept learned from a few examples with a library's SMCs as actions, tested on held-out
worlds and added to a library, so that the next concept can call it (docs/few_shot.md)."""

from __future__ import annotations

import os
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any

from sb3_smc.errors import SMCError, SMCTypeError
from sb3_smc.fewshot.choice import DEFAULT_OFFERED, Choice, choose_smcs, held_out
from sb3_smc.library import SMCLibrary
from sb3_smc.library.pretrained import pretrained_names, pretrained_root
from sb3_smc.smc.smc import SMC

__all__ = ["OFFERS", "Learned", "learn_concept", "learn_concepts", "offered_smcs"]

OFFERS = ("auto", "all", "none")
"""The ways of offering SMCs besides a curriculum's name or a list of names: the automatic choice from the examples,
the whole library (held out), or none (the flat SMC)."""

Libraries = SMCLibrary | str | os.PathLike | Sequence[SMCLibrary | str | os.PathLike] | None


class Learned:
    """What :func:`learn_concept` did: the trained ``smc`` (its test evaluation in ``smc.evaluations``), the names
    ``offered`` to it and, for the automatic choice, its ``choice`` (every candidate's score)."""

    def __init__(self, smc: SMC, offered: tuple[str, ...], choice: Choice | None) -> None:
        self.smc, self.offered, self.choice = smc, offered, choice

    def __repr__(self) -> str:
        return f"Learned({self.smc.name!r}, test score {self.smc.test_score}, offered {list(self.offered)})"


def _library(given: Libraries) -> SMCLibrary:
    """One library of everything ``given`` holds: ``"pretrained"`` (the package's), a folder, a library, or several
    (a name in two must be the same SMC)."""
    if given is None:
        return SMCLibrary()
    items = [given] if isinstance(given, SMCLibrary | str | os.PathLike) else list(given)
    merged = SMCLibrary()
    for item in items:
        if isinstance(item, SMCLibrary):
            library = item
        elif isinstance(item, str | os.PathLike):
            library = SMCLibrary.load(pretrained_root() if str(item) == "pretrained" else Path(item))
        else:
            raise SMCTypeError(f"library must be an SMCLibrary, a folder or 'pretrained', got {type(item).__name__}")
        for name in library.names:
            merged.add(library[name])
    return merged


def offered_smcs(library: Mapping[str, SMC], offer: str | Sequence[str], datasets: Sequence[str]) -> list[str]:
    """The SMCs ``offer`` names that may be offered to a concept of ``datasets`` (:func:`held_out`), before any
    automatic choice: ``"all"`` / ``"auto"`` the whole library, ``"none"`` nothing, a pretrained curriculum's name its
    lower-level SMCs, or a list of names. A named SMC trained on the concept's own datasets is refused."""
    allowed = held_out(library, datasets)
    if isinstance(offer, str) and offer in OFFERS:
        return [] if offer == "none" else allowed
    names = pretrained_names(offer) if isinstance(offer, str) else list(offer)
    missing = [name for name in names if name not in library]
    if missing:
        raise SMCError(f"offer names SMCs the library does not hold: {missing[:5]}")
    barred = [name for name in names if name not in allowed]
    if barred:
        raise SMCError(f"offer names SMCs trained on the concept's own datasets {list(datasets)}: {barred[:5]} "
                       "(held out: a concept never calls what was trained on its own worlds)")
    return names


def learn_concept(task: str, *, library: Libraries = "pretrained", offer: str | Sequence[str] = "auto",
                  train_worlds: int | None = None, k: int = DEFAULT_OFFERED, name: str | None = None, seed: int = 0,
                  repeats: int = 10, add_to: SMCLibrary | str | os.PathLike | None = None,
                  lean_update: bool = False, log_every: int | None = 0, **settings: Any) -> Learned:
    """Learn the concept of ``task`` from its training worlds (``train_worlds``: its first ``N``) with SMCs of
    ``library`` as actions, test it on every held-out world, and add it to ``add_to``.

    :param task: a PixelWorld id (``"PW-cl_self-in-container_vs_noncontainer-v0"``) or a user's own worlds
        registered with :func:`pixelworld_env.register_worlds`.
    :param library: ``"pretrained"`` (the package's), a library folder, an :class:`~sb3_smc.SMCLibrary`, several of
        them, or ``None`` (no SMC: with ``offer="none"``, the flat SMC).
    :param offer: ``"auto"`` (the automatic choice from the examples alone: :func:`~sb3_smc.fewshot.choose_smcs`),
        ``"all"`` (the whole library), ``"none"``, a pretrained curriculum's name (``"search2-canon"``: its set), or a
        list of names. SMCs trained on the concept's own datasets are never offered.
    :param train_worlds: how many training worlds (``None``: all of them).
    :param k: the automatic choice's number of SMCs.
    :param name: the new SMC's name (default: the task's, ``@seed``; ``-n<N>`` with ``train_worlds``).
    :param seed: the training seed (the choice's draws use it too).
    :param repeats: repeats of every test world (the paper's 10).
    :param add_to: a library (object or folder, created if missing) the SMC is added to, its children with it.
    :param settings: the other settings of :func:`~sb3_smc.train_smc` (``total_timesteps``, ``algo``,
        ``tensorboard_log``, ...; no ``callback``: :func:`learn_concepts`).
    :return: :class:`Learned`: the SMC, what was offered, the choice.
    """
    [learned] = learn_concepts(task, seeds=[seed], library=library, offer=offer, train_worlds=train_worlds, k=k,
                               names=[name] if name else None, repeats=repeats, lean_update=lean_update,
                               log_every=log_every, **settings)
    if add_to is not None:
        target = add_to if isinstance(add_to, SMCLibrary) else (
            SMCLibrary.load(add_to) if (Path(add_to) / "manifest.json").is_file() else SMCLibrary(path=add_to))
        learned = Learned(target.add(learned.smc), learned.offered, learned.choice)
        if not isinstance(add_to, SMCLibrary):
            target.save()
    return learned


def learn_concepts(task: str, *, seeds: Sequence[int], library: Libraries = "pretrained",
                   offer: str | Sequence[str] = "auto", train_worlds: int | None = None, k: int = DEFAULT_OFFERED,
                   names: Sequence[str] | None = None, repeats: int = 10, lean_update: bool = False,
                   log_every: int | None = 0, tensorboard_log: str | None = None,
                   printer: Callable[[str], None] = print, stop_at_max_return: bool = True,
                   **settings: Any) -> list[Learned]:
    """:func:`learn_concept` for each of ``seeds`` (``names``: the SMCs' names, one per seed), the SMCs trained
    together (:func:`~sb3_smc.learning.batched.train_smcs`: the seeds offered the same SMCs in one group), each the
    SMC ``learn_concept`` gives for its seed; then each tested on every held-out world. ``tensorboard_log``,
    ``printer`` and ``stop_at_max_return`` are ``train_smc``'s; ``settings`` its spec settings (``total_timesteps``,
    ``algo``, ...); a ``callback`` is refused (``train_smcs`` runs none)."""
    from sb3_smc.learning.batched import train_smcs
    from sb3_smc.learning.evaluation import evaluate
    from sb3_smc.learning.training import smc_spec
    from sb3_smc.records import TaskSpec
    from sb3_smc.records.spec import smc_name_from_env_id

    if not isinstance(offer, str | Sequence):
        raise SMCTypeError(f"offer must be one of {OFFERS}, a curriculum's name or a list of names, got {offer!r}")
    if "callback" in settings:
        raise SMCTypeError("learn_concept takes no callback: it trains through train_smcs, which runs none "
                           "(train_smc(..., callback=...) on the task with the same children does)")
    if names is not None and len(names) != len(seeds):
        raise SMCError(f"learn_concepts: {len(names)} names for {len(seeds)} seeds")
    task_spec = TaskSpec(task, env_kwargs={"train_worlds": train_worlds} if train_worlds else {}).resolved()
    if task_spec.kind is None:
        raise SMCError(f"{task}: not a task sb3_smc knows the kind of (a PW-* id or register_worlds' id)")
    datasets = task_spec.datasets or (task,)
    merged = _library(library)
    allowed = offered_smcs(merged, offer, datasets)
    stem = smc_name_from_env_id(task) + (f"-n{train_worlds}" if train_worlds else "")
    offers: list[tuple[tuple[str, ...], Choice | None]] = []
    specs = []
    for i, seed in enumerate(seeds):
        choice = None
        chosen = allowed
        if offer == "auto" and allowed:
            choice = choose_smcs(task, [merged[n] for n in allowed], train_worlds=train_worlds, k=k, seed=seed)
            chosen = list(choice.chosen)
        offers.append((tuple(chosen), choice))
        spec, _ = smc_spec(task, children=[merged[n] for n in chosen], seed=seed, train_worlds=train_worlds,
                           name=names[i] if names is not None else f"{stem}@{seed}", **settings)
        specs.append(spec)
    children = {n: merged[n] for chosen, _ in offers for n in chosen}
    smcs = train_smcs(specs, children=children, lean_update=lean_update, log_every=log_every,
                      tensorboard_log=tensorboard_log, printer=printer, stop_at_max_return=stop_at_max_return)
    for smc in smcs:
        evaluate(smc, repeats=repeats, seed=0, record_cells=False)
    return [Learned(smc, chosen, choice) for smc, (chosen, choice) in zip(smcs, offers, strict=True)]
