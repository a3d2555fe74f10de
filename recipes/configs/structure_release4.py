"""Release 4 of the structure model (jax3dc/release/MODEL_CARD.md, "Training"; run at cbb34fb,
``docs/runs/release4_20261128/run.sh``): from random ``mini`` weights with release 1's tokenizer, the
procedural build of 8,500 objects, 1,500 scenes and two views, and the real training pool in the
release-4 look (``--data``'s ``real_train_v2``: 8 views, mirror, palette per view) at a 0.3 share."""

from recipes.recipe import Data, Recipe, StructureCall

RECIPE = Recipe(release="jax3dc/release", calls=(
    ("release4", StructureCall(init="mini", tokenizer="jax3dc/release", objects=8500, scenes=1500, views=2,
                               augment=True, appearance="varied", real=Data("real_train_v2"), real_weight=0.3,
                               pivot_frame="box", steps=1400, lr=1e-3)),
))
