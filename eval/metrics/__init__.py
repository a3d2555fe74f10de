"""The paper's evaluation metrics (SPEC §5) for predicted structures.

``build_cases`` (from JSONL via ``load_references`` / ``load_predictions``) parses and
canonicalises both sides; ``evaluate`` returns the split metrics (metrics.json keys) and one row
per object; ``format_tables`` prints Tables 1 and 2.
"""

from eval.metrics.cases import Reference, build_cases, load_predictions, load_references, parse_prediction
from eval.metrics.score import TABLE1_KEYS, TABLE2_KEYS, Case, Evaluation, evaluate
from eval.metrics.tables import format_tables

__all__ = [
    "TABLE1_KEYS", "TABLE2_KEYS", "Case", "Evaluation", "Reference", "build_cases", "evaluate",
    "format_tables", "load_predictions", "load_references", "parse_prediction",
]
