"""Gymnasium ids for the whole catalog, registered in one place (on ``import pixelworld_env``).

* ``PW-<dataset>-v0`` for every dataset, e.g. ``PW-cl_self-in-container_vs_noncontainer-v0``;
* ``PW-<cl|ba>_<concept>-v0`` for every concept, pooling the datasets that share the concept and kind,
  e.g. ``PW-ba_self-in-container-v0``.

Every id also has a native vector environment: ``gymnasium.make_vec(id, num_envs=N)`` gives a
:class:`pixelworld_env.envs.vector.PixelWorldVectorEnv` (``vectorization_mode="sync"`` still gives ``SyncVectorEnv``).

Making an env loads (or generates, once) only the datasets it uses.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Literal

import gymnasium as gym

from pixelworld_env.datasets import catalog
from pixelworld_env.datasets.loading import Split, check_train_worlds, few_worlds, load_dataset
from pixelworld_env.envs.env import Observation, PixelWorldEnv, check_settings
from pixelworld_env.envs.vector import MAX_VECTOR_ENVS, RENDER_ENVS, PixelWorldVectorEnv
from pixelworld_env.errors import PixelWorldError
from pixelworld_env.validation import check_bool, check_count

ENTRY_POINT = "pixelworld_env.envs.registration:make_env"
VECTOR_ENTRY_POINT = "pixelworld_env.envs.registration:make_vector_env"


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
    if train_worlds is None:
        scenes, labels = [s for d in loaded for s in d.scenes], [label for d in loaded for label in d.labels]
    else:
        scenes, labels = few_worlds(loaded, train_worlds)
    env = PixelWorldEnv(
        scenes, kind=loaded[0].kind, concept=loaded[0].concept,
        labels=labels if loaded[0].kind == "classification" else None,
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
