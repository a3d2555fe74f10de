"""jax3dc's data_pipeline stage."""
