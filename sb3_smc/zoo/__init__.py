"""rl_zoo3 integration.

* ``rl_zoo3 train --algo trpo --env PW-...`` works as typed once sb3-smc is installed from a wheel: the
  interpreter start-up hook ``_sb3_smc_gym_hook`` registers the PW-* ids when Gymnasium is imported
  (``SB3_SMC_GYM_HOOK=0`` switches it off; ``--gym-packages pixelworld_env`` is the explicit fallback).
* ``--algo recurrent_trpo``: sb3-smc's :class:`~sb3_smc.recurrent_trpo.RecurrentTRPO`, added to rl_zoo3's algorithm
  table by the same hook when rl_zoo3 is imported.
* sb3-smc's hyperparameters: ``-conf sb3_smc.zoo.trpo`` / ``ppo`` / ``ppo_lstm`` / ``recurrent_trpo`` (conf
  modules) or the files of ``zoo_configs/`` (:mod:`sb3_smc.zoo.configs`, generated from the defaults:
  ``python -m sb3_smc.zoo zoo_configs``).
* Entries those configurations name: ``env_wrapper: sb3_smc.zoo.smc_env`` (SMC observation layout; SMCs of a
  library as actions with ``library`` / ``names``) and ``callback: sb3_smc.zoo.SMCZooCallback`` (TensorBoard).
* :func:`import_zoo_model` / ``sb3-smc import-zoo``: a zoo-trained model into an :class:`~sb3_smc.SMCLibrary`.
* ``python -m sb3_smc.zoo.record_video``: the zoo's ``record_video`` with the ids registered.
"""

from sb3_smc.zoo.configs import (
           CALLBACK,
           ENV_WRAPPER,
           ZOO_ALGOS,
           ZOO_POLICY_NAMES,
           hyperparams_for,
           render_config,
           write_configs,
)
from sb3_smc.zoo.entries import SMCZooCallback, smc_env
from sb3_smc.zoo.importing import ZooRunError, import_zoo_model, read_zoo_run

__all__ = ["CALLBACK", "ENV_WRAPPER", "ZOO_ALGOS", "ZOO_POLICY_NAMES", "SMCZooCallback", "ZooRunError",
           "hyperparams_for", "import_zoo_model", "read_zoo_run", "render_config", "smc_env", "write_configs"]
