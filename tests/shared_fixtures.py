"""The PartNet-Mobility samples in the workplace's shared folder (../shared/fixtures), which
their licence keeps out of the project tree. Tests need them: a missing folder is an error that
says where they are expected, never a silent skip."""

from pathlib import Path

PARTNET_MOBILITY = Path(__file__).resolve().parents[2] / "shared" / "fixtures" / "partnet_mobility"


def partnet_object(name: str) -> Path:
    """The folder of one sample object; fails loudly when the shared fixtures are absent."""
    folder = PARTNET_MOBILITY / name
    if not (folder / "mobility.urdf").is_file():
        raise FileNotFoundError(f"PartNet-Mobility fixture {name} not found at {folder}: the tests read "
                                "../shared/fixtures/partnet_mobility beside the repository")
    return folder
