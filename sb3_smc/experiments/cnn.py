"""The paper's passive CNN baseline: a classifier that sees the whole initial grid and never acts.

sb3-smc's choices where the paper leaves them open (docs/design.md, "The CNN baseline"):

* input: the initial 18 x 35 state array as one-hot channels of the colour codes 0, 1, 2, 3 and 7 (empty, white,
  red self, blue floor, purple frame: the codes of the classification datasets);
* two 3 x 3 convolutions (stride 1, same padding, ReLU) with 8 and 16 filters, a fully connected layer of 8 units
  (ReLU) and a 2-way output (softmax in the cross-entropy loss);
* Adam, learning rate 1e-3, weight decay 1e-3 (the "l2 regularization"), full batches of the 50 training
  environments, up to 300 epochs with early stopping on the training loss (stop when it has not improved by 1e-4
  for 30 epochs; the weights of the lowest loss are kept);
* test: accuracy on the 50 test environments; 5 seeds (torch's seed = the seed); the best seed is reported like
  the SMCs'.

One process, one torch thread, CPU: a few seconds per target and seed.
"""

from __future__ import annotations

import time
from dataclasses import asdict, dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from sb3_smc.common.threads import compute_threads
from sb3_smc.errors import SMCError

if TYPE_CHECKING:
    from torch import nn

__all__ = ["CHANNELS", "CNNResult", "encode", "train_cnn"]

CHANNELS = (0, 1, 2, 3, 7)
"""Colour codes given a channel each (other codes, absent from the classification data, map to none)."""
EPOCHS, PATIENCE, MIN_DELTA = 300, 30, 1e-4


@dataclass
class CNNResult:
    """One CNN run: the target, the seed, training loss and accuracy, test accuracy, epochs and wall time."""

    target: str
    seed: int
    train_loss: float
    train_accuracy: float
    test_score: float
    epochs: int
    wall_time_s: float

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)


def encode(grids: list[np.ndarray]) -> np.ndarray:
    """State arrays -> float32 one-hot tensors ``(n, len(CHANNELS), height, width)``."""
    stack = np.stack(grids)
    return np.stack([(stack == code) for code in CHANNELS], axis=1).astype(np.float32)


def _network(height: int, width: int) -> nn.Sequential:
    from torch import nn

    return nn.Sequential(
        nn.Conv2d(len(CHANNELS), 8, 3, padding=1), nn.ReLU(),
        nn.Conv2d(8, 16, 3, padding=1), nn.ReLU(),
        nn.Flatten(), nn.Linear(16 * height * width, 8), nn.ReLU(), nn.Linear(8, 2))


def train_cnn(target: str, seed: int, *, dataset_seed: int = 0, train_worlds: int | None = None) -> CNNResult:
    """Train the CNN on ``target``'s training split with ``seed`` and test it on the test split (one torch thread;
    the caller's count is restored). ``train_worlds=N``: on the first ``N`` worlds of the training split only (the
    order of ``gym.make(id, train_worlds=N)``); the test split is whole."""
    from pixelworld_env.datasets import catalog

    if catalog.dataset(target).kind != "classification":
        raise SMCError(f"the CNN baseline classifies: {target!r} is a bring-about dataset")
    with compute_threads(1):
        return _train(target, seed, dataset_seed, train_worlds)


def _train(target: str, seed: int, dataset_seed: int, train_worlds: int | None) -> CNNResult:
    import torch

    from pixelworld_env.datasets.loading import check_train_worlds, few_worlds, load_dataset

    train_worlds = check_train_worlds(train_worlds, "train")
    torch.manual_seed(seed)
    train = load_dataset(target, split="train", seed=dataset_seed)
    test = load_dataset(target, split="test", seed=dataset_seed)
    scenes, labels = few_worlds([train], train_worlds)
    x_train = torch.from_numpy(encode([s.grid() for s in scenes]))
    y_train = torch.tensor(labels, dtype=torch.long)
    x_test = torch.from_numpy(encode([s.grid() for s in test.scenes]))
    y_test = torch.tensor(test.labels, dtype=torch.long)
    net = _network(*x_train.shape[2:])
    optimiser = torch.optim.Adam(net.parameters(), lr=1e-3, weight_decay=1e-3)
    loss_fn = torch.nn.CrossEntropyLoss()
    start = time.perf_counter()
    best_loss, best_state, since, epochs = float("inf"), None, 0, 0
    for epoch in range(EPOCHS):
        optimiser.zero_grad()
        loss = loss_fn(net(x_train), y_train)  # the loss of the current weights: snapshot them before the step
        value = float(loss.detach())
        epochs = epoch + 1
        if value < best_loss - MIN_DELTA:
            best_loss, since = value, 0
            best_state = {k: v.detach().clone() for k, v in net.state_dict().items()}
        else:
            since += 1
            if since >= PATIENCE:
                break
        loss.backward()
        optimiser.step()
    if best_state is not None:
        net.load_state_dict(best_state)
    with torch.no_grad():
        train_accuracy = (net(x_train).argmax(1) == y_train).double().mean().item()
        test_score = (net(x_test).argmax(1) == y_test).double().mean().item()
        train_loss = float(loss_fn(net(x_train), y_train))
    return CNNResult(target=target, seed=seed, train_loss=train_loss, train_accuracy=train_accuracy,
                     test_score=test_score, epochs=epochs, wall_time_s=time.perf_counter() - start)
