"""Step-policy micro-benchmark: µs per call of the numpy actors of ``sb3_smc.smc.policies`` next to ``model.predict``.

An SMC called as a child runs one observation at a time, so this per-call cost bounds a level-2 SMC's speed. Cases
(models from ``untrained_smc(...)`` on a real PixelWorld task; the weights do not change the cost):
RecurrentPPO with the default LSTM-32 and ``net_arch=[]``, with a (64, 64) head, and PPO with a (64, 64) MLP; then
``sample_action`` next to ``numpy.random.Generator.choice``. Best of 5 blocks of ``--repeats`` calls.

A second table times the compiled step of the default architectures (``sb3_smc.common.kernels``: LSTM-32 and
GRU-32, ``net_arch=[]``) against the same policy's numpy code, for one row (``probabilities``) and for
``probabilities_batch`` on 2 and 4 rows (compiled: row by row; numpy code: one batched evaluation).

A third table times the learner's data-collection step (``SequenceLstmPolicy.forward`` / its GRU variant under
``torch.no_grad``, what ``RecurrentPPO.collect_rollouts`` calls once per vector step) for 16 environments: the compiled
step (``sb3_smc.common.kernels.*_collection_step``) against the same policy's torch step
(``compiled_collection = False``), each with ``obs_as_tensor`` as SB3 calls it.

Run: ``python benchmarks/bench_policies.py [--repeats N]``.
"""

from __future__ import annotations

import argparse
import copy
import time
from collections.abc import Callable

import numpy as np
import torch
from sb3_contrib.common.recurrent.type_aliases import RNNStates
from stable_baselines3.common.utils import obs_as_tensor

from sb3_smc.envs.factory import make_smc_env
from sb3_smc.learning.training import untrained_smc
from sb3_smc.smc.policies import policy_from_model, sample_action

ENV_ID = "PW-cl_self-in-left-corner_vs_on-hline-v0"


def best_us(call: Callable[[int], object], repeats: int, blocks: int = 5) -> float:
    """Best over ``blocks`` of the mean µs per call of ``call(i)`` over ``repeats`` calls (robust to a busy host)."""
    best = float("inf")
    for _ in range(blocks):
        start = time.perf_counter()
        for i in range(repeats):
            call(i)
        best = min(best, (time.perf_counter() - start) / repeats * 1e6)
    return best


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--repeats", type=int, default=1000, help="calls per block")
    args = parser.parse_args()
    torch.set_num_threads(1)
    cases = [("RecurrentPPO LSTM-32, net_arch=[] (default)", {}),
             ("RecurrentPPO LSTM-32, net_arch=[64, 64]", {"policy_kwargs": {"net_arch": [64, 64]}}),
             ("PPO MlpPolicy (64, 64)", {"algo": "PPO", "policy_kwargs": {"net_arch": [64, 64]}})]
    rows = []
    for label, settings in cases:
        smc = untrained_smc(ENV_ID, n_envs=1, **settings)
        env = make_smc_env(smc.spec)
        observations = [env.reset(seed=s)[0] for s in range(64)]
        policy, model = policy_from_model(smc.model), smc.model
        carried = {"numpy": policy.initial_state(), "sb3": None}

        def numpy_step(i: int, policy=policy, carried=carried, observations=observations) -> None:
            _, carried["numpy"] = policy.probabilities(observations[i % 64], carried["numpy"])

        def predict_step(i: int, model=model, carried=carried, observations=observations) -> None:
            _, carried["sb3"] = model.predict(observations[i % 64], state=carried["sb3"],
                                              episode_start=np.array([i == 0]))

        numpy_us, predict_us = best_us(numpy_step, args.repeats), best_us(predict_step, args.repeats)
        rows.append((label, numpy_us, predict_us))
    rng = np.random.default_rng(0)
    p = policy.probabilities(observations[0], policy.initial_state())[0]
    sample_us = best_us(lambda i: sample_action(p, rng), args.repeats * 10)
    choice_us = best_us(lambda i: rng.choice(len(p), p=p), args.repeats * 10)
    rows.append(("sample_action vs Generator.choice", sample_us, choice_us))

    compiled_rows = []
    for rnn in ("lstm", "gru"):
        compiled = policy_from_model(untrained_smc(ENV_ID, n_envs=1, rnn=rnn).model)
        numpy_code = copy.copy(compiled)
        numpy_code._compiled = None  # the same weights through the numpy code
        state = compiled.probabilities(observations[1], compiled.initial_state())[1]
        for rows_in_batch in (1, 2, 4):
            times = []
            for policy in (compiled, numpy_code):
                if rows_in_batch == 1:
                    times.append(best_us(lambda i, p=policy, s=state: p.probabilities(observations[i % 64], s),
                                         args.repeats))
                else:
                    x, s = np.stack(observations[:rows_in_batch]), [state] * rows_in_batch
                    times.append(best_us(lambda i, p=policy, x=x, s=s: p.probabilities_batch(x, s), args.repeats))
            compiled_rows.append((rnn.upper(), rows_in_batch, *times))

    collection_rows = []
    for rnn in ("lstm", "gru"):
        learner = untrained_smc(ENV_ID, n_envs=16, rnn=rnn).model.policy
        batch = np.stack(observations[:16])
        hidden = torch.zeros((1, 16, 32))
        states = RNNStates((hidden, hidden), (hidden, hidden))
        starts = torch.zeros(16)
        times = []
        for compiled_step in (True, False):
            learner.compiled_collection = compiled_step

            def collect(i: int, learner=learner, batch=batch, states=states, starts=starts) -> None:
                with torch.no_grad():
                    learner.forward(obs_as_tensor(batch, "cpu"), states, starts)

            times.append(best_us(collect, args.repeats))
        collection_rows.append((rnn.upper(), *times))

    print(f"\nbest of 5 x {args.repeats} calls; torch {torch.__version__}\n")
    print("| case | numpy (µs/call) | baseline: model.predict / choice (µs/call) | speed-up |")
    print("|---|---:|---:|---:|")
    for label, ours, theirs in rows:
        print(f"| {label} | {ours:.1f} | {theirs:.1f} | {theirs / ours:.1f}x |")
    print("\n| cell | rows | compiled (µs/call) | numpy code (µs/call) | speed-up |")
    print("|---|---:|---:|---:|---:|")
    for cell, rows_in_batch, ours, theirs in compiled_rows:
        print(f"| {cell}-32 | {rows_in_batch} | {ours:.1f} | {theirs:.1f} | {theirs / ours:.1f}x |")
    print("\n| learner's collection step, 16 environments | compiled (µs/call) | torch (µs/call) | speed-up |")
    print("|---|---:|---:|---:|")
    for cell, ours, theirs in collection_rows:
        print(f"| {cell}-32 | {ours:.1f} | {theirs:.1f} | {theirs / ours:.1f}x |")


if __name__ == "__main__":
    main()
