"""jax3dc's train stage."""
