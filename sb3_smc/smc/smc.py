"""Sensorimotor contingencies (SMCs): frozen policies with their action names and child SMCs.

An SMC acts on an environment through the action list of :func:`~sb3_smc.core.layout.smc_action_names`: the task's
signals, then (unless ``include_primitives`` is off) the environment's primitive actions, then one action per child
SMC. Its observation (:func:`~sb3_smc.core.layout.observation_size`) is the environment's sensor values, then one
outcome entry per child (+1 SIG1, -1 SIG0, 0 not called yet or timed out), then the one-hot of its previous action (all
zeros at the first step), as the paper's policy input. On PixelWorld (:data:`~sb3_smc.core.layout.PIXELWORLD_LAYOUT`)
the sensor is the one-hot 3 x 3 window (81 values) and the primitives are the four moves; on another environment they
are what its task gives (:mod:`sb3_smc.tasks.task`), recorded as the SMC's :class:`~sb3_smc.core.layout.Layout`.
"""

from __future__ import annotations

import hashlib
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Protocol, runtime_checkable

import numpy as np

from sb3_smc.core.layout import PIXELWORLD_LAYOUT, SIGNALS, Layout, observation_size, smc_action_names
from sb3_smc.core.names import check_name
from sb3_smc.errors import SMCError, SMCTypeError

if TYPE_CHECKING:
    from sb3_smc.records import EvaluationRecord, TrainingRecord, TrainingSpec


@runtime_checkable
class StepPolicy(Protocol):
    """What the wrapper needs to run a policy one observation at a time.

    ``initial_state()`` returns the recurrent state of a fresh call (``None`` for a memoryless policy);
    ``probabilities(obs, state)`` returns the action probabilities (1-D, summing to 1, one per action name)
    and the next state. Scripted policies (one-hot probabilities) and trained SB3 models (see
    :mod:`sb3_smc.smc.policies`) both follow it.
    """

    def initial_state(self) -> Any: ...

    def probabilities(self, observation: np.ndarray, state: Any) -> tuple[np.ndarray, Any]: ...


@dataclass
class SMC:
    """A sensorimotor contingency: a frozen policy, its action names and the SMCs it calls.

    ``model`` is the trained SB3 model when there is one (``None`` for scripted policies). Trained SMCs carry
    their provenance as typed records (:mod:`sb3_smc.records`): ``spec`` (how it was trained), ``record`` (what
    training produced) and ``evaluations`` (the latest :class:`~sb3_smc.records.EvaluationRecord` per env id and
    split, added by :func:`sb3_smc.evaluate`). A spec must agree with the SMC's kind, children and primitive
    setting. ``layout`` is the environment's sensor size and primitive actions (PixelWorld's by default); an SMC's
    children share it.
    """

    name: str
    kind: str
    policy: StepPolicy
    children: tuple[SMC, ...] = ()
    include_primitives: bool = True
    model: Any = None
    spec: TrainingSpec | None = None
    record: TrainingRecord | None = None
    evaluations: tuple[EvaluationRecord, ...] = ()
    layout: Layout = PIXELWORLD_LAYOUT

    def __post_init__(self) -> None:
        check_name(self.name, "SMC name")
        if not isinstance(self.layout, Layout):
            raise SMCTypeError(f"SMC {self.name!r}: layout must be a Layout, got {type(self.layout).__name__}")
        if self.kind not in SIGNALS:
            raise SMCError(f"SMC {self.name!r}: kind must be one of {tuple(SIGNALS)}, got {self.kind!r}")
        self.children = tuple(self.children)
        names = [child.name for child in self.children]
        if len(set(names)) != len(names):
            raise SMCError(f"SMC {self.name!r}: child names must be unique, got {names}")
        if _calls(self, self.name):
            raise SMCError(f"SMC {self.name!r} calls itself (directly or through its children)")
        other = [child.name for child in self.children if child.layout != self.layout]
        if other:
            raise SMCError(f"SMC {self.name!r}: the children {other} act on another environment layout than its own "
                           f"({self.layout})")
        self.evaluations = tuple(self.evaluations)
        if self.spec is not None:
            spec = self.spec
            found = {"kind": (spec.task.kind, self.kind), "children": (spec.children, tuple(names)),
                     "include_primitives": (spec.wrapper.include_primitives, self.include_primitives),
                     "layout": (spec.task.smc_layout, self.layout)}
            wrong = {k: v for k, v in found.items() if v[0] != v[1]}
            if wrong:
                detail = "; ".join(f"{k}: spec {a!r}, SMC {b!r}" for k, (a, b) in wrong.items())
                raise SMCError(f"SMC {self.name!r}: its training spec does not match it ({detail})")

    @classmethod
    def from_spec(cls, spec: TrainingSpec, policy: StepPolicy, children: Sequence[SMC] = (), *, name: str | None = None,
                  model: Any = None, record: TrainingRecord | None = None,
                  evaluations: Sequence[EvaluationRecord] = ()) -> SMC:
        """The SMC trained by ``spec``: its kind, primitives setting and layout are the spec's, its ``children`` the
        SMCs the spec names (in its order), its name the spec's unless ``name`` is given."""
        if spec.task.kind is None:
            raise SMCError(f"SMC {spec.name!r}: the kind of task {spec.task.env_id!r} is not known")
        return cls(spec.name if name is None else name, spec.task.kind, policy, tuple(children),
                   spec.wrapper.include_primitives, model=model, spec=spec, record=record,
                   evaluations=tuple(evaluations), layout=spec.task.smc_layout)

    def __deepcopy__(self, memo: dict) -> SMC:
        # An SMC is frozen once built: copies of env specs, wrappers and configs share it (its model may hold
        # torch tensors that cannot be deep-copied, and copying a policy per env would waste memory).
        return self

    @property
    def action_names(self) -> tuple[str, ...]:
        return smc_action_names(self.kind, [c.name for c in self.children], self.include_primitives,
                                self.layout.primitives)

    @property
    def observation_size(self) -> int:
        return observation_size(len(self.children), len(self.action_names), self.layout.sensor_size)

    @property
    def test_score(self) -> float | None:
        """The score of the latest evaluation on the test split of the SMC's own task (else of any test split)."""
        from sb3_smc.records import test_score_of

        return test_score_of(self.spec, self.evaluations)

    def add_evaluation(self, evaluation: EvaluationRecord) -> None:
        """Keep ``evaluation``, replacing an earlier one of the same env id and split."""
        if evaluation.smc != self.name:
            raise SMCError(f"evaluation of SMC {evaluation.smc!r} given to SMC {self.name!r}")
        self.evaluations = (*(e for e in self.evaluations if e.key != evaluation.key), evaluation)

    def check_layout(self, caller: str | None = None) -> None:
        """``ValueError`` unless this SMC's policy and those of its descendants take the observation and give the
        actions they will get as SMCs (checked from the policy's ``observation_size`` / ``n_actions`` where it
        declares them; a ``FrameStackPolicy`` declares its frame size and stack)."""
        where = f"SMC {self.name!r}" + (f" (called by {caller!r})" if caller else "")
        size, n_actions = self.observation_size, len(self.action_names)
        policy = self.policy
        layout = self.layout.describe(len(self.children), n_actions)
        declared = getattr(policy, "observation_size", None)
        stack = getattr(policy, "n_stack", None)
        inner = getattr(getattr(policy, "inner", None), "observation_size", None)
        if stack is not None and inner is not None and inner != stack * size:
            raise SMCError(f"{where}: its policy stacks {stack} frames of {declared} values into {inner} inputs, but "
                           f"as an SMC it gets frames of {size} ({layout})")
        if declared is not None and declared != size:
            raise SMCError(f"{where}: its policy expects observations of {declared} values, but as an SMC it gets "
                           f"{size} ({layout}); was it trained with other children or actions?")
        declared_actions = getattr(policy, "n_actions", None)
        if declared_actions is not None and declared_actions != n_actions:
            raise SMCError(f"{where}: its policy gives {declared_actions} action probabilities, but its actions are "
                           f"{n_actions}: {list(self.action_names)}")
        for child in self.children:
            child.check_layout(self.name)

    @property
    def digest(self) -> str | None:
        """The SHA-256 of the trained weights this SMC stands for: its model's policy weights (names, dtypes, shapes
        and values) and its children's digests in order. Two SMCs with the same digest have the same weights and call
        SMCs with the same weights, whichever file, machine or run made them (how they are wrapped, its spec, is
        not part of it); ``None`` where it or an SMC it calls has no trained model (a scripted policy)."""
        policy = getattr(self.model, "policy", None)
        children = [child.digest for child in self.children]
        if policy is None or None in children:
            return None
        digest = hashlib.sha256()
        for key, tensor in policy.state_dict().items():
            values = tensor.detach().cpu().numpy()
            digest.update(f"{key} {values.dtype} {values.shape}".encode())
            digest.update(np.ascontiguousarray(values).tobytes())
        for child in children:
            digest.update(f"child {child}".encode())
        return digest.hexdigest()

    @property
    def depth(self) -> int:
        """1 for an SMC without children, else 1 + the deepest child's depth."""
        return 1 + max((c.depth for c in self.children), default=0)


def _calls(smc: SMC, name: str) -> bool:
    return any(child.name == name or _calls(child, name) for child in smc.children)
