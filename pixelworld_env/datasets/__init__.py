"""The benchmark's datasets: the catalog of the release (``catalog``, over ``pixelworld_env/data/catalog.json``),
the disk cache of generated datasets (``cache``) and ``load_dataset`` (``loading``). Builds on ``generation``."""
