"""GRU recurrence for sb3-contrib's ``RecurrentPPO`` (the paper's GRU-32 policy; sb3-contrib only has LSTMs).

sb3-contrib's recurrent machinery (rollout buffer, ``RNNStates``, ``predict``) carries an LSTM's ``(h, c)`` pair.
:class:`~sb3_smc.common.recurrent.layers.GRUAsLSTM` runs a ``torch.nn.GRU`` behind that interface: it takes
``(h, c)``, uses ``h`` and returns the GRU's new ``h`` with ``c`` unchanged (zeros from the first step on, so the
buffers stay valid and never matter).
:class:`SequenceGruPolicy` is :class:`~sb3_smc.common.recurrent.policies.SequenceLstmPolicy` (fast training pass,
lean collection step, compact buffer) with GRUs in place of the LSTMs.
"""

from __future__ import annotations

from typing import Any

from sb3_smc.common.recurrent.layers import GRUAsLSTM
from sb3_smc.common.recurrent.policies import SequenceLstmPolicy

__all__ = ["SequenceGruPolicy"]


class SequenceGruPolicy(SequenceLstmPolicy):
    """:class:`~sb3_smc.common.recurrent.policies.SequenceLstmPolicy` with one (or ``n_lstm_layers``) GRU layers of
    ``lstm_hidden_size`` units instead of LSTMs, for the actor and, with ``enable_critic_lstm``, the critic.

    Select it with ``train_smc(..., rnn="gru")``; it saves and loads through ``RecurrentPPO.load`` like any SB3
    policy, and :func:`sb3_smc.smc.policies.policy_from_model` turns it into a
    :class:`~sb3_smc.smc.numpy_actors.NumpyGRUPolicy`.
    """

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        size, layers = self.lstm_output_dim, self.lstm_hidden_state_shape[0]
        # sb3-contrib types these as nn.LSTM; a GRUAsLSTM is one by duck typing (same calls, same state layout)
        self.lstm_actor = GRUAsLSTM(self.features_dim, size, layers, **self.lstm_kwargs)  # type: ignore[assignment]
        if self.lstm_critic is not None:
            self.lstm_critic = GRUAsLSTM(  # type: ignore[assignment]
                self.features_dim, size, layers, **self.lstm_kwargs)
        # the optimizer the parent built holds the LSTMs' parameters: rebuild it over the GRUs'
        learning_rate = self.optimizer.param_groups[0]["lr"]  # lr_schedule(1), as the parent used
        # SB3 types optimizer_class as type[Optimizer], whose base __init__ takes no lr (every real one does)
        self.optimizer = self.optimizer_class(  # type: ignore[call-arg]
            self.parameters(), lr=learning_rate, **self.optimizer_kwargs)
