"""Where a process's candidate launches go (``jax3dc.physics.launcher``): the local launcher until a
pool's initializer installs a device service's client, and a launcher's shapes on the launcher."""

from __future__ import annotations

from jax3dc.physics.launcher import LocalLauncher, ProcessDevice, process_launcher
from jax3dc.physics.mjx_service import DeviceClient


def test_a_process_launches_locally_until_a_client_is_installed():
    device = ProcessDevice()
    assert device.launcher() is device.local
    client = DeviceClient(0, requests=None, reply=None, crossings=True)
    device.client = client
    assert device.launcher() is client
    assert isinstance(process_launcher(), LocalLauncher)  # this test process runs no pool worker


def test_a_local_launcher_starts_with_no_shapes():
    launcher = LocalLauncher()
    assert launcher.penetration is None and launcher.crossing is None
