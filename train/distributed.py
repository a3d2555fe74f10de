"""Joining several processes (hosts) into one JAX runtime, configured from the environment.

Set on every process, before it starts:

    JAX_COORDINATOR_ADDRESS  host:port of process 0 (reachable from all processes)
    JAX_NUM_PROCESSES        how many processes take part
    JAX_PROCESS_ID           this process's index, 0 .. JAX_NUM_PROCESSES - 1

Under SLURM or Open MPI (several tasks) jax finds these itself. With none of them set the
run is single-process and nothing happens. On CPU the processes exchange data through gloo.
This must run before anything else touches a JAX device.
"""

from __future__ import annotations

import os

import jax

from train.config import ConfigError


def _cluster_detected() -> bool:
    return int(os.environ.get("SLURM_NTASKS", "1")) > 1 or int(os.environ.get("OMPI_COMM_WORLD_SIZE", "1")) > 1


def initialize_from_env() -> bool:
    """Call jax.distributed.initialize when the environment describes several processes.

    Returns True when this process is now part of a multi-process run.
    """
    address = os.environ.get("JAX_COORDINATOR_ADDRESS")
    if address:
        try:
            n = int(os.environ["JAX_NUM_PROCESSES"])
            rank = int(os.environ["JAX_PROCESS_ID"])
        except (KeyError, ValueError):
            raise ConfigError("JAX_COORDINATOR_ADDRESS is set: JAX_NUM_PROCESSES and JAX_PROCESS_ID "
                              "must be set to integers too") from None
        if not 0 <= rank < n:
            raise ConfigError(f"JAX_PROCESS_ID={rank} is outside 0..{n - 1}")
        if n == 1:
            return False
        jax.config.update("jax_cpu_collectives_implementation", "gloo")
        jax.distributed.initialize(coordinator_address=address, num_processes=n, process_id=rank)
        return True
    if _cluster_detected():
        jax.distributed.initialize()
        return True
    return False
