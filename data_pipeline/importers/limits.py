"""Caps on what one imported object may make us load, and the check that mesh files stay inside
the object's folder.

Imported files come from datasets and the web. Without caps, an OBJ of 5 million faces on 4
vertices or an MJCF whose ``<replicate>`` nests to millions of bodies takes minutes and gigabytes
before anything fails; each cap is refused in one line that names it and the flag that raises it.
A mesh path may also point anywhere (``../``, an absolute path, a symbolic link): reading it would
copy a file from outside the object into the converted output, so it is refused unless the user
allows it. (``package://`` URIs are kept inside their ROS package instead: see ``ros_package``.)
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from jax3dc.errors import InputFileError

DEFAULT_MAX_FACES = 2_000_000
"""Triangles of one object, all its mesh files together (PartNet-Mobility's largest are ~1 M)."""
DEFAULT_MAX_BODIES = 10_000
"""Bodies of one MJCF model after ``<replicate>`` is expanded."""


@dataclass(frozen=True)
class ImportLimits:
    """What one import may load; the ``data convert`` flags of the same names raise them."""

    max_faces: int = DEFAULT_MAX_FACES
    max_bodies: int = DEFAULT_MAX_BODIES
    allow_outside: bool = False


def inside_folder(path: Path, folder: Path, referenced_by: Path, where: str, limits: ImportLimits,
                  what: str = "mesh") -> Path:
    """``path`` with symbolic links resolved; InputFileError when it leaves ``folder`` and the user
    has not passed --allow-outside."""
    resolved = path.resolve()
    if limits.allow_outside or resolved.is_relative_to(folder.resolve()):
        return resolved
    raise InputFileError(referenced_by, f"{where}: {what} {path} lies outside the object's folder {folder} "
                                        f"(it resolves to {resolved}); pass --allow-outside to read it")


class FaceBudget:
    """Faces loaded so far for one object, against ``limits.max_faces``."""

    def __init__(self, limits: ImportLimits):
        self.limits = limits
        self.used = 0

    def check(self, faces: int, what: str, referenced_by: Path, where: str) -> None:
        """InputFileError naming the piece (``what``: "mesh FILE", "<box>") and the cap when ``faces``
        more would exceed it."""
        if self.used + faces > self.limits.max_faces:
            raise InputFileError(referenced_by, f"{where}: {what} brings the object to {self.used + faces} faces; "
                                                f"the cap is {self.limits.max_faces} (raise it with --max-faces)")

    def admit(self, faces: int, what: str, referenced_by: Path, where: str) -> None:
        """Count ``faces`` more, after checking them."""
        self.check(faces, what, referenced_by, where)
        self.used += faces
