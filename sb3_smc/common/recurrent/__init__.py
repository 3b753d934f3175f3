"""Fast recurrent training for sb3-contrib's ``RecurrentPPO``: sequence LSTM and GRU policies and a compact rollout
buffer.

:class:`SequenceLstmPolicy` computes what ``MlpLstmPolicy`` computes on every real step of its training pass (its
one-step collection path equals it up to float rounding); :class:`CompactRecurrentRolloutBuffer` yields the stock
minibatches without padding (tested to 1e-6); :class:`SequenceGruPolicy` is the same policy with GRUs.
"""

from sb3_smc.common.recurrent.buffers import CompactRecurrentRolloutBuffer, use_compact_buffer
from sb3_smc.common.recurrent.gru import SequenceGruPolicy
from sb3_smc.common.recurrent.layers import GRUAsLSTM
from sb3_smc.common.recurrent.policies import SequenceLstmPolicy
from sb3_smc.common.recurrent.type_aliases import SequenceStates

__all__ = ["CompactRecurrentRolloutBuffer", "GRUAsLSTM", "SequenceGruPolicy", "SequenceLstmPolicy", "SequenceStates",
           "use_compact_buffer"]
