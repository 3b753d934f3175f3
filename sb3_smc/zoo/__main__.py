"""``python -m sb3_smc.zoo [DIRECTORY]``: write the rl_zoo3 hyperparameter files (default ``zoo_configs/``)."""

import argparse

from sb3_smc.zoo.configs import write_configs

parser = argparse.ArgumentParser(description="Write the rl_zoo3 hyperparameter files (zoo_configs/*.yml).")
parser.add_argument("directory", nargs="?", default="zoo_configs")
for path in write_configs(parser.parse_args().directory):
    print(f"wrote {path}")
