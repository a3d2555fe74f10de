"""Run an accuracy evaluator by name: ``python3 -m eval.evaluate NAME [ARGS...]``.

``python3 -m eval.evaluate`` alone lists the evaluators; ``NAME --help`` gives one's settings.
"""

from __future__ import annotations

import sys
from collections.abc import Sequence

from eval.evaluators import EVALUATORS, evaluator


def listing() -> str:
    width = max(map(len, EVALUATORS))
    return "\n".join(f"  {e.name:<{width}}  {e.summary}" for e in EVALUATORS.values())


def main(argv: Sequence[str] | None = None) -> int:
    args = list(sys.argv[1:] if argv is None else argv)
    if not args or args[0] in ("-h", "--help"):
        print(f"usage: python3 -m eval.evaluate NAME [ARGS...]\n\nevaluators:\n{listing()}")
        return 0
    result = evaluator(args[0]).run(args[1:])
    return result if isinstance(result, int) else 0


if __name__ == "__main__":
    sys.exit(main())
