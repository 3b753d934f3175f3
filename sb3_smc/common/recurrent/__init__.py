"""Fast recurrent training for sb3-contrib's ``RecurrentPPO``: a sequence LSTM policy and a compact rollout buffer.

Neither changes a number: :class:`SequenceLstmPolicy` computes what ``MlpLstmPolicy`` computes on every real step,
and :class:`CompactRecurrentRolloutBuffer` yields the stock minibatches without padding (tested to 1e-6).
"""

from sb3_smc.common.recurrent.buffers import CompactRecurrentRolloutBuffer, use_compact_buffer
from sb3_smc.common.recurrent.policies import SequenceLstmPolicy
from sb3_smc.common.recurrent.type_aliases import SequenceStates

__all__ = ["CompactRecurrentRolloutBuffer", "SequenceLstmPolicy", "SequenceStates", "use_compact_buffer"]
