"""The peak device memory a run logs: the largest over its devices, absent where none is counted."""

from __future__ import annotations

import jax

from train.metrics_log import peak_memory_gib


class _Device:
    def __init__(self, stats):
        self._stats = stats

    def memory_stats(self):
        return self._stats


def test_largest_device_in_gib():
    devices = [_Device({"peak_bytes_in_use": 2**30}), _Device({"peak_bytes_in_use": 3 * 2**30}), _Device(None)]
    assert peak_memory_gib(devices) == 3.0


def test_none_where_no_device_counts():
    assert peak_memory_gib([_Device(None), _Device({"bytes_in_use": 5})]) is None


def test_this_backend_answers():
    value = peak_memory_gib(jax.local_devices())
    assert value is None or value >= 0
