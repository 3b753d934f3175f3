"""rl_zoo3 conf module: ``rl_zoo3 train --algo recurrent_trpo --env PW-... -conf sb3_smc.zoo.recurrent_trpo``
trains sb3-smc's RecurrentTRPO with its default hyperparameters (those of ``zoo_configs/recurrent_trpo.yml``)."""

from sb3_smc.zoo.configs import hyperparams_for

hyperparams = hyperparams_for("recurrent_trpo")
