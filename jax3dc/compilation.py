"""Compilation, shared by the commands that compile (train, the MJX sweep): JAX's persistent
cache, so a repeated or resumed run loads its executables from disk instead of compiling them
again; and a clock of where compile time goes (tracing, lowering, XLA), read from jax.monitoring."""

from __future__ import annotations

import os
import threading

DEFAULT_DIR = "~/.cache/jax3dc/xla"
# jax.monitoring's duration events of one jit compile, by the name a report gives them
PHASES = {"/jax/core/compile/jaxpr_trace_duration": "trace_s",
          "/jax/core/compile/jaxpr_to_mlir_module_duration": "lower_s",
          "/jax/core/compile/backend_compile_duration": "xla_s"}

CACHE_HIT = "/jax/compilation_cache/cache_hits"  # inside the XLA phase: the executable came from the cache

_totals = dict.fromkeys(PHASES.values(), 0.0) | {"xla_programs": 0, "cache_hits": 0}
_lock = threading.Lock()
_listening = False


def use_compile_cache(directory: str) -> None:
    """Cache compiled executables in ``directory`` ("" turns it off); the environment's
    JAX_COMPILATION_CACHE_DIR, where set, wins."""
    if directory and "JAX_COMPILATION_CACHE_DIR" not in os.environ:
        import jax  # lazy: jax (0.39 s) stays out of `import jax3dc.physics.cli`, which reads DEFAULT_DIR only

        jax.config.update("jax_compilation_cache_dir", os.path.expanduser(directory))


def _on_duration(event: str, seconds: float, **_) -> None:
    phase = PHASES.get(event)
    if phase is None:
        return
    with _lock:
        _totals[phase] += seconds
        _totals["xla_programs"] += phase == "xla_s"


def _on_event(event: str, **_) -> None:
    if event == CACHE_HIT:
        with _lock:
            _totals["cache_hits"] += 1


def _listen() -> None:
    """Installs the one process-wide listener (jax.monitoring has no per-caller removal)."""
    global _listening
    with _lock:
        if _listening:
            return
        _listening = True
    import jax  # lazy: as in use_compile_cache (0.39 s)

    jax.monitoring.register_event_duration_secs_listener(_on_duration)
    jax.monitoring.register_event_listener(_on_event)


class CompileClock:
    """Seconds spent tracing, lowering and in XLA, the programs XLA compiled and those it loaded
    from the persistent cache instead, since it was made (in every thread of the process). A
    cache hit's XLA seconds are the time to load it."""

    def __init__(self) -> None:
        _listen()
        self._start = self._now()

    @staticmethod
    def _now() -> dict[str, float]:
        with _lock:
            return dict(_totals)

    def elapsed(self) -> dict[str, float]:
        """trace_s, lower_s, xla_s, compiles and cache_hits."""
        now = self._now()
        d = {k: now[k] - self._start[k] for k in now}
        d["compiles"] = d.pop("xla_programs") - d["cache_hits"]
        return d
