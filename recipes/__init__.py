"""The recipes that make the shipped weights: each shipped model's recipe is a small typed config
(``recipes/configs/``) that one trainer module runs (``release_model`` for the structure model,
``stage1_net`` for the stage-1 image network, ``stage1_model`` for a stage-1 language model).

Recipes sit above every other package: they build data (``data_pipeline``), train (``train``) and
score (``eval``) through the commands a user runs, and nothing imports them.
"""
