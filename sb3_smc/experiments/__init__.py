"""The paper's experiments: one command from curricula to results and a report (docs/design.md, "Selection and
test").

* :mod:`sb3_smc.experiments.design` — methods, the level-2 targets by category, the nodes of each method;
* :mod:`sb3_smc.experiments.cnn` — the passive CNN baseline;
* :mod:`sb3_smc.experiments.runner` — :func:`run_experiment`: train, evaluate, ``results.csv`` / ``results.json``;
* :mod:`sb3_smc.experiments.report` — :func:`write_report`: ``report.md`` and figures (of one directory or several),
  the paper's numbers beside;
* :mod:`sb3_smc.experiments.statistics` — seed summaries, means ± s.e., t-tests, win counts, the claims table;
* :mod:`sb3_smc.experiments.paper` — the paper's numbers.
"""

from sb3_smc.experiments.design import CATEGORIES, DEFAULT_METHODS, METHODS, level2_targets, plan

__all__ = ["CATEGORIES", "DEFAULT_METHODS", "METHODS", "level2_targets", "plan", "run_experiment", "write_report"]


def __getattr__(name: str):
    if name == "run_experiment":
        from sb3_smc.experiments.runner import run_experiment

        return run_experiment
    if name == "write_report":
        from sb3_smc.experiments.report import write_report

        return write_report
    raise AttributeError(f"module 'sb3_smc.experiments' has no attribute {name!r}")
