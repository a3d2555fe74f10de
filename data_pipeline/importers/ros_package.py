"""ROS ``package://<pkg>/<path>`` mesh URIs, resolved within the named package and never outside it.

A ROS package is the folder holding a ``package.xml`` whose ``<name>`` is ``<pkg>``. Without a ROS
workspace to ask, the package is looked for where a robot description ships it: the URDF's own
folder or a folder above it (``my_robot/package.xml`` beside ``my_robot/urdf/robot.urdf`` and
``my_robot/meshes/``). A URI names a file inside its package, so a path that leaves the package
(``..``, a symbolic link pointing out) is refused whatever ``--allow-outside`` says: that flag is
for plain paths, and a package URI that escapes is malformed, not a user's choice.
"""

from __future__ import annotations

from pathlib import Path

from data_pipeline.importers.safe_xml import parse_xml
from jax3dc.errors import InputFileError

PACKAGE_PREFIX = "package://"
MANIFEST = "package.xml"


def _package_name(manifest: Path) -> str | None:
    """The ``<name>`` of a package.xml; None when it is unreadable, malformed or has no name."""
    try:
        root = parse_xml(manifest, "package")
    except InputFileError:
        return None
    name = root.findtext("name")
    return name.strip() if name and name.strip() else None


class PackageResolver:
    """Resolves the package URIs of one URDF; each package's root is looked up once."""

    def __init__(self, urdf: Path):
        self.urdf = Path(urdf)
        self.roots: dict[str, Path] = {}

    def root(self, name: str, uri: str, where: str) -> Path:
        """The folder of package ``name``: the nearest one at or above the URDF's folder whose
        package.xml names it. InputFileError naming the URI and the folders searched otherwise."""
        if name in self.roots:
            return self.roots[name]
        start = self.urdf.parent.resolve()
        seen = []
        for folder in (start, *start.parents):
            manifest = folder / MANIFEST
            if manifest.is_file():
                found = _package_name(manifest)
                if found == name:
                    self.roots[name] = folder
                    return folder
                seen.append(f"{manifest} names {found!r}" if found else f"{manifest} is unreadable or has no <name>")
        others = f" ({'; '.join(seen)})" if seen else ""
        raise InputFileError(self.urdf, f"{where}: {uri!r}: package {name!r} not found: no {MANIFEST} with "
                                        f"<name>{name}</name> in {start} or a folder above it{others}")

    def resolve(self, uri: str, where: str) -> Path:
        """The file a ``package://`` URI names, with symbolic links resolved; InputFileError when
        the URI is malformed, its package unknown, or the path leaves the package."""
        package, _, rest = uri[len(PACKAGE_PREFIX):].partition("/")
        if not package or not rest:
            raise InputFileError(self.urdf, f"{where}: {uri!r} is not package://<package>/<path to a file>")
        root = self.root(package, uri, where)
        path = root / rest
        resolved = path.resolve()
        if not resolved.is_relative_to(root):
            raise InputFileError(self.urdf, f"{where}: {uri!r} leaves package {package!r} at {root}: "
                                            f"{path} resolves to {resolved}; a package URI must stay in its package")
        return resolved
