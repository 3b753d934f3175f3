"""The class path ``sb3_smc.training.SequenceLstmPolicy``, which SB3 archives saved by sb3-smc 0.1 pickled (a
library of version 1): unpickling one imports it from here. Nothing else lives here; training is
:mod:`sb3_smc.learning.training`. A library converted to the current version (``sb3-smc library DIR --upgrade
--trust``) names the class at :mod:`sb3_smc.common.recurrent.policies` and needs this module no more.
"""

from sb3_smc.common.recurrent.policies import SequenceLstmPolicy

__all__ = ["SequenceLstmPolicy"]
