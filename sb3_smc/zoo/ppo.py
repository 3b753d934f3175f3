"""rl_zoo3 conf module: ``rl_zoo3 train --algo ppo --env PW-... -conf sb3_smc.zoo.ppo`` trains with sb3-smc's
hyperparameters (those of ``zoo_configs/ppo.yml``) for every PW-* id."""

from sb3_smc.zoo.configs import hyperparams_for

hyperparams = hyperparams_for("ppo")
