"""A new concept from a few examples, with a library of learned SMCs as its actions (docs/few_shot.md):
:func:`~sb3_smc.fewshot.learn.learn_concept` (and :func:`~sb3_smc.fewshot.learn.learn_concepts` for several
seeds at once), the automatic choice of SMCs to offer
(:func:`~sb3_smc.fewshot.choice.choose_smcs`) and the held-out rule (:func:`~sb3_smc.fewshot.choice.held_out`)."""

from sb3_smc.fewshot.choice import DEFAULT_OFFERED, Choice, choose_smcs, held_out
from sb3_smc.fewshot.learn import OFFERS, Learned, learn_concept, learn_concepts, offered_smcs

__all__ = ["DEFAULT_OFFERED", "OFFERS", "Choice", "Learned", "choose_smcs", "held_out", "learn_concept",
           "learn_concepts", "offered_smcs"]
