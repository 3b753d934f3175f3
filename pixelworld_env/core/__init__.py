"""The engine: colours and object classes, the shape library, container regions, scenes, the mutable world with its
compiled physics (``kernels``), and rendering. Imports nothing of the other sub-packages."""
