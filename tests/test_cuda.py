"""The recurrent learners on a CUDA device (skipped where torch sees no GPU). ``train_smc`` always trains on the CPU,
but a user may build ``RecurrentTRPO`` or ``RecurrentPPO`` with the sequence policies on a GPU (``device="auto"``
picks one): they must learn there, skip the CPU-only compiled collection step, save and load onto the CPU, and give
the numpy actor the library stores."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
import torch
from sb3_contrib import RecurrentPPO

from sb3_smc import SMC, SMCLibrary, evaluate
from sb3_smc.core.hyperparameters import constructor_arguments
from sb3_smc.learning.training import make_vec_env
from sb3_smc.records import TrainingSpec
from sb3_smc.recurrent_trpo import RecurrentTRPO
from sb3_smc.smc.policies import policy_from_model
from tests.test_recurrent_trpo import CORNER_ID, _recall_rate, _recurrent

DEVICE = "cuda"
pytestmark = pytest.mark.skipif(not torch.cuda.is_available(), reason="needs a CUDA device")


@pytest.mark.parametrize("learner", [RecurrentPPO, RecurrentTRPO])
def test_both_recurrent_learners_solve_the_memory_task_on_cuda(learner) -> None:
    """The CPU run (test_recurrent_trpo) recalls the cue in all 200 episodes after 10,000 steps; so must a GPU run."""
    model = _recurrent(learner, seed=0, device=DEVICE)
    assert all(p.device.type == DEVICE for p in model.policy.parameters())
    with warnings.catch_warnings():  # no recurrent call on unpacked weights outside RecurrentTRPO's search
        warnings.filterwarnings("error", "RNN module weights are not part", UserWarning)
        model.learn(10_000)
    assert _packed(model)  # RecurrentTRPO's parameter swaps would otherwise leave cuDNN to repack at every call
    assert _recall_rate(model) >= 0.95


def _packed(model) -> bool:
    """Whether each recurrent layer's weights are views of one buffer (cuDNN's packed layout)."""
    layers = [m for m in model.policy.modules() if isinstance(m, torch.nn.RNNBase)]
    return bool(layers) and all(len({w.untyped_storage().data_ptr() for w in m._flat_weights}) == 1 for m in layers)


def _smc_model(algo: str, rnn: str) -> tuple[RecurrentPPO, TrainingSpec]:
    """An SMC's model (``algo``: RecurrentPPO or RecurrentTRPO) built on the device, on the SMC environment of
    ``CORNER_ID``, after one update."""
    spec = TrainingSpec.create(CORNER_ID, algo=algo, rnn=rnn)
    env = make_vec_env(spec)
    policy_class, settings = constructor_arguments(spec.hyperparameters)
    model = {"RecurrentPPO": RecurrentPPO, "RecurrentTRPO": RecurrentTRPO}[algo](
        policy_class, env, n_steps=64, seed=0, device=DEVICE, **settings)
    model.learn(64 * env.num_envs)
    assert _packed(model)
    return model, spec


@pytest.mark.parametrize(("algo", "rnn"),
                         [("RecurrentPPO", "gru"), ("RecurrentTRPO", "lstm"), ("RecurrentTRPO", "gru")])
def test_a_cuda_model_saves_loads_onto_the_cpu_and_gives_its_numpy_actor(algo, rnn, tmp_path) -> None:
    model, _ = _smc_model(algo, rnn)
    env = model.get_env()
    assert model.policy._collection_parameters() is None  # the compiled step is CPU-only: the stock forward runs
    model.save(tmp_path / "model.zip")
    loaded = type(model).load(tmp_path / "model.zip", device="cpu")
    assert loaded.policy._collection_parameters() is not None
    for (name, a), (_, b) in zip(model.policy.state_dict().items(), loaded.policy.state_dict().items(), strict=True):
        assert torch.equal(a.cpu(), b), name
    obs = np.stack([env.observation_space.sample() for _ in range(6)])
    starts = np.ones(6, dtype=bool)
    with torch.no_grad():
        on_gpu = model.policy.get_distribution(torch.as_tensor(obs, device=DEVICE), _zeros(model, 6, DEVICE),
                                               torch.as_tensor(starts, dtype=torch.float32, device=DEVICE))[0]
        on_cpu = loaded.policy.get_distribution(torch.as_tensor(obs), _zeros(loaded, 6, "cpu"),
                                                torch.as_tensor(starts, dtype=torch.float32))[0]
    gpu_probs = on_gpu.distribution.probs.cpu().numpy()
    np.testing.assert_allclose(gpu_probs, on_cpu.distribution.probs.numpy(), atol=1e-5)
    actor = policy_from_model(model)  # copied off the GPU
    for k in range(6):
        np.testing.assert_allclose(actor.probabilities(obs[k], actor.initial_state())[0], gpu_probs[k], atol=1e-5)


def _zeros(model, n: int, device: str) -> tuple[torch.Tensor, torch.Tensor]:
    """Zero recurrent states for ``n`` sequences on ``device``."""
    shape = model.policy.lstm_hidden_state_shape
    return torch.zeros(shape[0], n, shape[2], device=device), torch.zeros(shape[0], n, shape[2], device=device)


def test_an_smc_of_a_cuda_model_goes_into_a_library_and_loads_onto_the_cpu(tmp_path) -> None:
    model, spec = _smc_model("RecurrentTRPO", "gru")
    smc = SMC.from_spec(spec, policy_from_model(model), model=model)
    again = SMCLibrary.load(SMCLibrary([smc]).save(tmp_path / "library"))[smc.name]
    assert all(p.device.type == "cpu" for p in again.model.policy.parameters())
    assert evaluate(again, repeats=1).score == evaluate(smc, repeats=1).score
