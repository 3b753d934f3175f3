"""The SMC: ``SMC`` and the ``StepPolicy`` protocol (``smc``), step policies (``policies``) and the numpy actors
(``numpy_actors``). Builds on ``core`` and the records.

The names of the old module ``sb3_smc.smc`` (now ``smc``) are re-exported here: the path still works."""

from sb3_smc.smc.smc import *  # noqa: F403
