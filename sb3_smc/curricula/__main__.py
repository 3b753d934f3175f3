"""``python -m sb3_smc.curricula [DIR]``: write the shipped curricula (``sb3_smc/curricula/data/*.yml``)."""

from sb3_smc.curricula.shipped import main

main()
