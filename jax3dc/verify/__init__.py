"""Verified decoding (issue 32): the physics verdict (SPEC §8) picks among sampled candidates and
repairs the joints it flags.

``select.choose`` ranks candidate texts; ``repair.repair`` tries alternatives for flagged joints;
``verdicts.VerdictCache`` checks each distinct structure once for both; ``verified.verify_object``
chooses and repairs one object, ``pool.verify_many`` many objects in worker processes. ``predict``
runs the choice and the repair as steps of its own (each writes a file); evaluation runs the pool
over a split's records (``eval/run_verify.py``).
"""
