"""Verified decoding (issue 32): the physics verdict (SPEC §8) picks among sampled candidates and
repairs the joints it flags.

``data_pipeline.record_parts`` rebuilds a record's part meshes (what the verdict needs beside a structure);
``select.choose`` ranks candidate texts; ``repair.repair`` tries alternatives for flagged joints;
``pool.verify_many`` runs many objects at once in separate processes.
"""
