"""``python -m sb3_smc.zoo.record_video [rl_zoo3 record_video arguments]``: rl_zoo3's ``record_video`` for PW-* ids.

rl_zoo3's ``record_video`` has no ``--gym-packages``; installed (a wheel or ``pip install -e``), sb3-smc registers
the ids when Gymnasium is imported (``_sb3_smc_gym_hook``), so ``python -m rl_zoo3.record_video`` works too. This
launcher registers them explicitly first (for ``SB3_SMC_GYM_HOOK=0``, or a source tree on ``PYTHONPATH``) and then
runs the zoo's module
unchanged, e.g. ``python -m sb3_smc.zoo.record_video --algo trpo --env PW-... -f logs -n 100 -o videos``.
"""

import runpy

import pixelworld_env  # noqa: F401  (registers the PW-* ids)

runpy.run_module("rl_zoo3.record_video", run_name="__main__", alter_sys=True)
