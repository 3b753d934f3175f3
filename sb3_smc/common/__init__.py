"""Pieces shared by the learners (kept apart from the SMC layer, as in sb3-contrib)."""
