"""Dataset generation: the readers of the original definition and experiment files, ``DatasetSpec``, the seeded
constraint search of a generator (``sampling``, ``placement``; ``csp`` for verification), the planner that checks
bring-about goals (``oracle``) and ``generate`` (``dataset``). Builds on ``core`` and ``concepts``."""
