"""The vocabulary every stage reads, torch-free: what an SMC senses and does (``layout``), the learners and their
hyperparameters (``hyperparameters``), names in children-first order (``dag``). Imports no other stage."""
