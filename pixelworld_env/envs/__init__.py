"""The Gymnasium side: ``PixelWorldEnv`` (``env``), the native vector env (``vector``) and the ``PW-*`` ids
(``registration``). Builds on ``core``, ``concepts`` and, for the registered ids, ``datasets``."""
