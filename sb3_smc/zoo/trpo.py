"""rl_zoo3 conf module: ``rl_zoo3 train --algo trpo --env PW-... -conf sb3_smc.zoo.trpo`` trains with sb3-smc's
hyperparameters (those of ``zoo_configs/trpo.yml``) for every PW-* id."""

from sb3_smc.zoo.configs import hyperparams_for

hyperparams = hyperparams_for("trpo")
