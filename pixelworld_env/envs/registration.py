"""Gymnasium ids for the whole catalog, registered in one place (on ``import pixelworld_env``).

* ``PW-<dataset>-v0`` for every dataset, e.g. ``PW-cl_self-in-container_vs_noncontainer-v0``;
* ``PW-<cl|ba>_<concept>-v0`` for every concept, pooling the datasets that share the concept and kind,
  e.g. ``PW-ba_self-in-container-v0``;
* a user's own worlds as a task, registered by :func:`register_worlds` (training and test worlds, their labels or
  the goal): the same environment, splits and ``train_worlds`` as the catalog's ids.

Every id also has a native vector environment: ``gymnasium.make_vec(id, num_envs=N)`` gives a
:class:`pixelworld_env.envs.vector.PixelWorldVectorEnv` (``vectorization_mode="sync"`` still gives ``SyncVectorEnv``).

Making an env loads (or generates, once) only the datasets it uses.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Literal

import gymnasium as gym

from pixelworld_env.concepts import Concept
from pixelworld_env.core.kinds import Kind, task_kind
from pixelworld_env.core.scene import Scene
from pixelworld_env.datasets import catalog
from pixelworld_env.datasets.loading import Dataset, Split, check_train_worlds, few_worlds, load_dataset
from pixelworld_env.envs.env import Observation, PixelWorldEnv, check_settings, default_labels
from pixelworld_env.envs.vector import MAX_VECTOR_ENVS, RENDER_ENVS, PixelWorldVectorEnv
from pixelworld_env.errors import PixelWorldError, PixelWorldTypeError
from pixelworld_env.validation import check_bool, check_count

ENTRY_POINT = "pixelworld_env.envs.registration:make_env"
VECTOR_ENTRY_POINT = "pixelworld_env.envs.registration:make_vector_env"
WORLDS_ENTRY_POINT = "pixelworld_env.envs.registration:make_worlds_env"
WORLDS_VECTOR_ENTRY_POINT = "pixelworld_env.envs.registration:make_worlds_vector_env"


def env_id(name: str) -> str:
    """The Gymnasium id of a dataset or concept pool."""
    return f"PW-{name}-v0"


def make_env(datasets: Sequence[str], *, split: Split = "train", seed: int = 0, max_steps: int = 100,
             observation: Observation = "hand", render_mode: str | None = None,
             aaai18_reset_bug: bool = False, train_worlds: int | None = None) -> PixelWorldEnv:
    """A :class:`PixelWorldEnv` over the scenes of one or more catalog datasets sharing kind and concept.

    ``seed`` is the dataset-generation seed (the episode seed goes to ``reset``); ``split`` picks the
    stratified train or test half, or "all". ``train_worlds=N``: only the first ``N`` worlds of the training split in
    its fixed order (:func:`pixelworld_env.datasets.loading.training_order`: nested, stratified by label, a pool's
    members in turn); refused on another split. The other arguments are :class:`PixelWorldEnv`'s; all are checked
    before any dataset is loaded.
    """
    check_settings(max_steps=max_steps, observation=observation, render_mode=render_mode,
                   aaai18_reset_bug=aaai18_reset_bug)
    train_worlds = check_train_worlds(train_worlds, split)
    loaded = [load_dataset(name, split=split, seed=seed) for name in datasets]
    kinds = {d.kind for d in loaded}
    concepts = {d.concept for d in loaded}
    if len(kinds) != 1 or len(concepts) != 1:
        raise PixelWorldError(f"datasets {list(datasets)} do not share one kind and concept")
    scenes, labels = few_worlds(loaded, train_worlds)
    env = PixelWorldEnv(
        scenes, kind=loaded[0].kind, concept=loaded[0].concept,
        labels=labels if task_kind(loaded[0].kind).label is not None else None,
        macros=catalog.macros(), max_steps=max_steps, observation=observation, render_mode=render_mode,
        aaai18_reset_bug=aaai18_reset_bug,
    )
    env.split = split
    env.train_worlds = train_worlds
    return env


def make_vector_env(num_envs: int = 1, *, datasets: Sequence[str], split: Split = "train", seed: int = 0,
                    max_steps: int = 100, observation: Observation = "hand", render_mode: str | None = None,
                    aaai18_reset_bug: bool = False, render_envs: Literal["all", "first"] = "all",
                    train_worlds: int | None = None) -> PixelWorldVectorEnv:
    """``num_envs`` environments of :func:`make_env` as one :class:`~pixelworld_env.envs.vector.PixelWorldVectorEnv`
    (the ids' ``vector_entry_point``); settings the vector env refuses (``num_envs`` above ``MAX_VECTOR_ENVS``
    among them) are refused before any dataset is loaded."""
    check_count(num_envs, "num_envs", MAX_VECTOR_ENVS, "pixelworld_env.envs.vector.MAX_VECTOR_ENVS")
    if check_bool(aaai18_reset_bug, "aaai18_reset_bug") or render_mode == "human" or render_envs not in RENDER_ENVS:
        PixelWorldVectorEnv.check_settings(aaai18_reset_bug=aaai18_reset_bug, render_mode=render_mode,
                                           render_envs=render_envs)
    env = make_env(datasets, split=split, seed=seed, max_steps=max_steps, observation=observation,
                   render_mode=render_mode, aaai18_reset_bug=aaai18_reset_bug, train_worlds=train_worlds)
    return PixelWorldVectorEnv(env, num_envs, render_envs=render_envs)


def registered_ids() -> dict[str, tuple[str, ...]]:
    """Every PixelWorld id -> the datasets it samples from."""
    ids: dict[str, tuple[str, ...]] = {env_id(name): (name,) for name in catalog.dataset_names()}
    ids.update({env_id(pool): members for pool, members in catalog.concept_pools().items()})
    return ids


def register_envs() -> None:
    """Register every id of :func:`registered_ids` with Gymnasium (idempotent)."""
    for name, members in registered_ids().items():
        if name not in gym.registry:
            gym.register(name, entry_point=ENTRY_POINT, vector_entry_point=VECTOR_ENTRY_POINT,
                         kwargs={"datasets": members})


@dataclass(frozen=True)
class Worlds:
    """A user's own task as data: its kind, concept (the goal of a bring-about task; a classification task's is a
    description, its labels say what holds), and its training and test worlds with their labels
    (:func:`register_worlds`)."""

    name: str
    kind: Kind
    concept: str
    train: Dataset
    test: Dataset

    def split(self, split: Split) -> list[Dataset]:
        return {"train": [self.train], "test": [self.test], "all": [self.train, self.test]}[split]


def _scenes(worlds: Sequence[Scene | str], what: str, kinds: Mapping[str, str] | None) -> tuple[Scene, ...]:
    if isinstance(worlds, str | Scene) or not isinstance(worlds, Sequence) or not worlds:
        raise PixelWorldTypeError(f"{what} must be a non-empty list of Scene objects or ASCII drawings")
    return tuple(w if isinstance(w, Scene) else Scene.from_ascii(w, kinds) for w in worlds)


def _labels(labels: Sequence[int] | None, scenes: tuple[Scene, ...], what: str, kind: str,
            concept: str) -> tuple[int, ...]:
    """The worlds' labels: none for a kind without labels (all 1, as the catalog stores them), the user's for
    classification, the user's or the exhaustive search's for bring-about-or-cannot (1: possible)."""
    described = task_kind(kind)
    if described.label is None:
        if labels is not None:
            raise PixelWorldError(f"{what}: a {kind} task has no labels (its goal is the concept)")
        return (1,) * len(scenes)
    if labels is None and described.label == "possible":
        return tuple(default_labels(described, Concept(concept, catalog.macros()), scenes))
    if labels is None or len(labels) != len(scenes) or any(
            isinstance(v, bool) or v not in (0, 1) for v in labels):
        raise PixelWorldError(f"{what}: a {kind} task needs one label, 0 or 1, per world ({len(scenes)} "
                              f"worlds), got {labels!r}")
    return tuple(int(v) for v in labels)


def register_worlds(env_id: str, *, kind: Kind, concept: str,
                    train: Sequence[Scene | str], test: Sequence[Scene | str],
                    train_labels: Sequence[int] | None = None, test_labels: Sequence[int] | None = None,
                    kinds: Mapping[str, str] | None = None) -> str:
    """Register a user's own worlds as a Gymnasium id, a task like the catalog's: ``gym.make(env_id, split="test")``,
    ``train_worlds=N``, the native vector env (``gym.make_vec``). Returns ``env_id``.

    :param kind: ``"classification"`` (labels required), ``"bring-about"`` (``concept`` is the goal; no labels) or
        ``"bring-about-or-cannot"`` (labels 1 where the goal can be brought about, 0 where not; without them each
        world is searched exhaustively).
    :param concept: a formula of the concept language (``"?x container(x) & inside_supported(self,x)"``).
    :param train: the training worlds, :class:`~pixelworld_env.Scene` objects or drawings as
        :meth:`Scene.from_ascii` takes them (``kinds``: its letters' shape families).
    :param test: held-out worlds, for the test split.
    :raises PixelWorldError: an id already registered, labels that do not fit, worlds of different sizes.
    """
    if not isinstance(env_id, str) or not env_id:
        raise PixelWorldTypeError(f"env_id must be a non-empty string, got {env_id!r}")
    if env_id in gym.registry:
        raise PixelWorldError(f"{env_id!r} is registered already; choose another id")
    task_kind(kind)
    parts = {}
    for split, scenes, labels in (("train", train, train_labels), ("test", test, test_labels)):
        drawn = _scenes(scenes, f"{split} worlds", kinds)
        parts[split] = Dataset(name=env_id, kind=kind, concept=concept, split=split, seed=0, scenes=drawn,
                               labels=_labels(labels, drawn, f"{split} worlds", kind, concept))
    worlds = Worlds(env_id, kind, concept, parts["train"], parts["test"])
    make_worlds_env(worlds)  # the concept parses, the worlds fit together: refused here, not at the first gym.make
    gym.register(env_id, entry_point=WORLDS_ENTRY_POINT, vector_entry_point=WORLDS_VECTOR_ENTRY_POINT,
                 kwargs={"worlds": worlds})
    return env_id


def make_worlds_env(worlds: Worlds, *, split: Split = "train", max_steps: int = 100, observation: Observation = "hand",
                    render_mode: str | None = None, train_worlds: int | None = None) -> PixelWorldEnv:
    """The :class:`PixelWorldEnv` of a task of :func:`register_worlds` (its entry point), as :func:`make_env` makes a
    catalog id's."""
    check_settings(max_steps=max_steps, observation=observation, render_mode=render_mode)
    train_worlds = check_train_worlds(train_worlds, split)
    scenes, labels = few_worlds(worlds.split(split), train_worlds)
    env = PixelWorldEnv(scenes, kind=worlds.kind, concept=worlds.concept,
                        labels=labels if task_kind(worlds.kind).label is not None else None, macros=catalog.macros(),
                        max_steps=max_steps, observation=observation, render_mode=render_mode)
    env.split, env.train_worlds = split, train_worlds
    return env


def make_worlds_vector_env(num_envs: int = 1, *, worlds: Worlds, split: Split = "train", max_steps: int = 100,
                           observation: Observation = "hand", render_mode: str | None = None,
                           train_worlds: int | None = None) -> PixelWorldVectorEnv:
    """``num_envs`` environments of :func:`make_worlds_env` as one native vector env."""
    check_count(num_envs, "num_envs", MAX_VECTOR_ENVS, "pixelworld_env.envs.vector.MAX_VECTOR_ENVS")
    env = make_worlds_env(worlds, split=split, max_steps=max_steps, observation=observation,
                          render_mode=render_mode, train_worlds=train_worlds)
    return PixelWorldVectorEnv(env, num_envs)

