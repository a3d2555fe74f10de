"""Release 5 of the structure model (jax3dc/release/MODEL_CARD.md; run at c77eb8a,
``docs/runs/release6_20261205/``): release 4's model and tokenizer from random ``mini`` weights, with
no domain in the look — every source rendered plain or varied per view (``--appearance mixed``),
the factories' objects also with their handles fused in, the real pool in both looks
(``--data``'s ``real_train``: 8 views, mirror, palette per view, mixed look) at a 0.3 share and
objects composed from real part meshes (``composed``: ``data build --composed 3000 --parts
real_parts``) at 0.15; 1,500 steps, the trainer alone on the GPU with 14 loader workers.

Its procedural build is ``docs/runs/release6_20261205/run.sh data proc`` (4,120 objects of seed 0,
and 800 objects with 100 scenes of seed 1 inside the same folder), put in ``OUT/release5/data``
before the call; the trainer builds only the first of the two when the folder is empty."""

from recipes.recipe import Data, Recipe, Share, StructureCall

RECIPE = Recipe(release="jax3dc/release", calls=(
    ("release5", StructureCall(init="mini", tokenizer="jax3dc/release", objects=4120, scenes=0, views=2,
                               augment=True, appearance="mixed", fuse_handles=True, real=Data("real_train"),
                               real_weight=0.3, mix=(Share(Data("composed"), 0.15),), pivot_frame="box",
                               steps=1500, lr=1e-3, heldout=Data("heldout_plain"),
                               heldout_varied=Data("heldout_varied"), fixtures=Data("fixtures_plain"),
                               fixtures_varied=Data("fixtures_varied"), set=("loader_workers=14",))),
))
