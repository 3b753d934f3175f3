"""SMC libraries: trained SMCs in a directory with a versioned manifest.

* :mod:`sb3_smc.library.library` — :class:`SMCLibrary`, the API (a mapping name -> SMC; add, save, load, wrap);
* :mod:`sb3_smc.library.manifest` — the manifest: its schema (version 6), the checksums of its content,
  :class:`LibraryEntry`, validation, the load order;
* :mod:`sb3_smc.library.model_file` — a model as a file that loads without running code (safetensors + JSON);
* :mod:`sb3_smc.library.upgrade` — manifests of versions 1 to 4, converted on read;
* :mod:`sb3_smc.library.pretrained` — the shipped pretrained library: its index, names by curriculum;
* :mod:`sb3_smc.library.storage` — the files: reading and writing the manifest, model files and checksums, adding
  and removing SMCs in place under the library's lock, the save that merges another writer's additions;
* :mod:`sb3_smc.library.errors` — the :class:`LibraryError` family.
"""

from sb3_smc.library.errors import (
    CorruptModelError,
    LayoutMismatchError,
    LibraryConflictError,
    LibraryError,
    ManifestError,
    MissingChildError,
    UnknownSMCError,
    UntrustedModelError,
)
from sb3_smc.library.library import SMCLibrary
from sb3_smc.library.manifest import FORMAT, FORMAT_VERSION

__all__ = [
    "FORMAT",
    "FORMAT_VERSION",
    "CorruptModelError",
    "LayoutMismatchError",
    "LibraryConflictError",
    "LibraryError",
    "ManifestError",
    "MissingChildError",
    "SMCLibrary",
    "UnknownSMCError",
    "UntrustedModelError",
]
