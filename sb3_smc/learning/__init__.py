"""Learning an SMC: ``train_smc`` (``training``), many at once (``batched``), the training callback (``callbacks``),
the signal bias (``bias``), the CNN features extractor (``features``) and the test protocol (``evaluation``).
Builds on every stage before it."""
