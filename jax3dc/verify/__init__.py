"""Verified decoding (issue 32): the physics verdict (SPEC §8) picks among sampled candidates and
repairs the joints it flags.

``select.choose`` ranks candidate texts; ``repair.repair`` tries alternatives for flagged joints;
``verdicts.VerdictCache`` checks each distinct structure once for both. Evaluation runs them over a
split's records (``eval/run_verify.py``, many objects at once in ``eval/run_verify_pool.py``).
"""
