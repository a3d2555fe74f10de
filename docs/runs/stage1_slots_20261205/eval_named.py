import json, sys
from pathlib import Path
from recipes.stage1_slots import evaluate, load_records
rows = load_records([sys.argv[2]], "test", 128, 24, 1)
summary, per = evaluate(Path(sys.argv[1]), rows)
print(json.dumps(summary))
