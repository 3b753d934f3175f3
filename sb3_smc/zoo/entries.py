"""What rl_zoo3 hyperparameter files name: the ``env_wrapper`` entry :func:`smc_env` and the ``callback`` entry
:class:`SMCZooCallback`."""

from __future__ import annotations

import functools
import sys
from collections.abc import Sequence
from typing import TYPE_CHECKING

from pixelworld_env.envs.env import PixelWorldEnv
from sb3_smc.envs.factory import task_base, wrap_with_smcs
from sb3_smc.errors import SMCError, SMCTypeError
from sb3_smc.learning.callbacks import SMCTrainingCallback
from sb3_smc.library import SMCLibrary
from sb3_smc.records import WrapperSettings

if TYPE_CHECKING:
    import gymnasium as gym

    from sb3_smc.envs.wrapper import HierarchicalSMCWrapper

__all__ = ["SMCZooCallback", "smc_env"]

_ANNOUNCED: set[tuple[str, str | None]] = set()


@functools.lru_cache(maxsize=8)
def _library(path: str) -> SMCLibrary:
    return SMCLibrary.load(path)


def smc_env(env: gym.Env, library: str | None = None, names: Sequence[str] = (), include_primitives: bool = True,
            count_primitive_steps: bool = False, call_step_cap: int = 100) -> HierarchicalSMCWrapper:
    """rl_zoo3 ``env_wrapper`` entry: ``env`` with the SMCs ``names`` of the library at ``library`` as actions.

    ``env`` is a PixelWorld environment or an SMC task on any environment (:class:`~sb3_smc.tasks.task.SMCTask`, its
    module given to rl_zoo3 as ``--gym-packages``). Without ``library`` the env gets no SMC actions: a flat SMC's
    layout (sensor, previous action). The library is
    loaded once per process and path. The first env of each id and split in a process prints one line naming the
    split it serves (``rl_zoo3 enjoy`` evaluates on what it says: pass ``--env-kwargs split:"'test'"`` for the test
    environments).
    """
    if names and library is None:
        raise SMCError(f"smc_env: names {list(names)} given without the library they come from")
    smcs = [_library(str(library))[name] for name in names] if library is not None else []
    settings = WrapperSettings(include_primitives=include_primitives, count_primitive_steps=count_primitive_steps,
                               call_step_cap=call_step_cap)
    base = task_base(env)
    env_id = getattr(getattr(env, "spec", None), "id", None) or type(base).__name__
    split = base.split if isinstance(base, PixelWorldEnv) else None
    key = (env_id, split)
    if key not in _ANNOUNCED:
        _ANNOUNCED.add(key)
        calls = f", SMC actions {list(names)} from {library}" if names else ""
        if isinstance(base, PixelWorldEnv):
            serves = f"the {split!r} split" if split is not None else "its own scenes (no split)"
            print(f"sb3-smc: {env_id} serves {serves}: {len(base.scenes)} environments{calls}", file=sys.stderr)
        else:
            print(f"sb3-smc: {env_id} serves its environment's own start states (an SMC task){calls}",
                  file=sys.stderr)
    return wrap_with_smcs(env, smcs, settings)


class SMCZooCallback(SMCTrainingCallback):
    """rl_zoo3 ``callback`` entry: :class:`~sb3_smc.learning.callbacks.SMCTrainingCallback`'s ``smc/`` and
    ``smc_calls/`` TensorBoard curves (accuracy or success rate, training return, calls per child, ...) in a zoo run.

    It takes no arguments: the task kind and the child SMCs are read from the training environments (built by
    :func:`smc_env`) when training starts. Name it in the hyperparameters as ``callback:
    sb3_smc.zoo.SMCZooCallback`` (the shipped configurations do).
    """

    def __init__(self, log_every: int = 0, verbose: int = 0) -> None:
        super().__init__(kind="classification", log_every=log_every, name="zoo", verbose=verbose)

    def _on_training_start(self) -> None:
        env = self.training_env
        try:
            self.kind = env.get_attr("kind")[0]
            self.children = tuple(smc.name for smc in env.get_attr("smcs")[0])
        except AttributeError as error:
            raise SMCTypeError("SMCZooCallback needs PixelWorld training environments inside sb3_smc.zoo.smc_env "
                               "(env_wrapper: sb3_smc.zoo.smc_env in the hyperparameters)") from error
        super()._on_training_start()
