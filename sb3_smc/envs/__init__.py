"""The SMC's environments: the step's rules (``smc_step``), ``HierarchicalSMCWrapper`` (``wrapper``), the vector envs
(``gymnasium_vec_env``, ``vec_env``) and the one environment factory (``factory``). Builds on ``core``, ``tasks``,
the records and ``smc``.

The names of the old module ``sb3_smc.envs`` (now ``factory``) are re-exported here: the path still works."""

from sb3_smc.envs.factory import *  # noqa: F403
