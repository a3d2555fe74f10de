"""jax3dc's eval stage."""
