"""rl_zoo3 conf module: ``rl_zoo3 train --algo ppo_lstm --env PW-... -conf sb3_smc.zoo.ppo_lstm`` trains with sb3-smc's
hyperparameters (those of ``zoo_configs/ppo_lstm.yml``) for every PW-* id."""

from sb3_smc.zoo.configs import hyperparams_for

hyperparams = hyperparams_for("ppo_lstm")
