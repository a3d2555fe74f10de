"""Qwen3-VL in Flax NNX."""
