"""The shipped factory network's parts as boxes on the held-out fifth's rest views (stage 1 only),
scored as eval.metrics.part_boxes scores the slots network's, for the same records."""
import io, json, sys
from pathlib import Path
import numpy as np
from PIL import Image
from data_pipeline.shards import read_dataset
from eval.metrics.part_boxes import score_part_boxes, summarise
from eval.metrics.part_matching import box_bounds
from jax3dc.geometry.parts import part_boxes
from jax3dc.predict.stage1 import ReaderSettings, load_reader, stage1_from_parameters
from jax3dc.stage1_slots.kinds import kind_of
from jax3dc.structure.boxes import boxes_from_dict

read = load_reader(Path("jax3dc/release/stage1"), ReaderSettings(sampler=None, max_new_tokens=512, constrained=True))
scores, rows = [], []
for rec in read_dataset(Path(sys.argv[1])):
    if rec.meta.get("view") != 0 or rec.meta.get("augmentation"):
        continue
    rgb = np.asarray(Image.open(io.BytesIO(rec.image_png)).convert("RGB"))
    text = read(rgb)
    s1 = stage1_from_parameters(text)
    pred = box_bounds(part_boxes(s1.parts)); ref = box_bounds(boxes_from_dict(rec.meta["boxes"]))
    names = rec.meta.get("part_names") or {}
    ri, pi = sorted(ref), sorted(pred)
    sc = score_part_boxes(rec.key, [ref[i] for i in ri], [kind_of(names[str(i)]) if str(i) in names else None for i in ri],
                          [pred[i] for i in pi], [kind_of(s1.names.get(i)) for i in pi])
    scores.append(sc); rows.append({"key": rec.key, "category": s1.category, **sc.to_dict()})
print(json.dumps(summarise(scores)))
Path(sys.argv[2]).write_text("\n".join(json.dumps(r) for r in rows) + "\n")
