"""Tasks: ``TaskEnv`` and ``SMCTask`` (``task``), a task spec resolved once (``resolved_task``). Builds on ``core``.

The names of the old module ``sb3_smc.tasks`` (now ``task``) are re-exported here: the path still works."""

from sb3_smc.tasks.task import *  # noqa: F403
