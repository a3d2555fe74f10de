"""Release 5 of the stage-1 image network (jax3dc/release/stage1/MODEL_CARD.md, "Data and recipe";
``docs/runs/stage1_box_20261202/``): candidate c from scratch, d = c trained on alone, then release 5
= d fine-tuned with the discrete values weighted 3. ``--data`` holds the builds: D-0 ... D-10 (seeds
0-10: four one-view builds, seven two-view), R-0 ... R-3 and F-8 ... F-14 (release 4's own sets)."""

from recipes.recipe import Data, Earlier, Recipe, Stage1NetCall, Work

BUILDS = tuple(Data(f"D-{seed}") for seed in range(11))
METRICS = Work("metrics.jsonl")  # the box metrics by parameter text, shared by the three calls

RECIPE = Recipe(release="jax3dc/release/stage1", calls=(
    ("c", Stage1NetCall(data=BUILDS, image_size=128, widths=(32, 64, 128, 256), blocks=2, hidden=512, batch=256,
                        lr=2e-3, steps=60000, minutes=8, number_weight=1, box_weight=4, box_cache=METRICS)),
    ("d", Stage1NetCall(data=BUILDS, init=Earlier("c"), image_size=128, hidden=512, batch=256, lr=1e-3, steps=60000,
                        minutes=5.5, number_weight=1, box_weight=4, box_cache=METRICS)),
    ("release5", Stage1NetCall(data=tuple(Data(n) for n in ("R-0", "R-1", "R-2", "R-3", "F-8", "F-9", "F-10", "F-12",
                                                            "F-13", "F-14")),
                               init=Earlier("d"), batch=64, lr=3e-4, steps=1400, minutes=22, number_weight=1,
                               box_weight=4, discrete_weight=3, box_cache=METRICS, compare=Earlier("d"))),
))
