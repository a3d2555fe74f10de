"""Reading untrusted XML (URDF, MJCF) without entity expansion.

Files come from datasets and the web, so a document type declaration is refused outright: no
internal entities (billion laughs), no external entities (file disclosure). Every failure is an
InputFileError that names the file and, where the parser knows it, the line.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
import xml.parsers.expat as expat
from pathlib import Path

from jax3dc.errors import InputFileError


class _Forbidden(Exception):
    pass


def _refuse(*_args) -> None:
    raise _Forbidden


def parse_xml(path: Path, root_tag: str | None = None) -> ET.Element:
    """Parse ``path`` after checking it has no DOCTYPE/ENTITY (and, if given, its root tag)."""
    try:
        data = Path(path).read_bytes()
    except OSError as e:
        raise InputFileError(path, f"cannot read file: {e.strerror or e}") from None
    checker = expat.ParserCreate()
    checker.StartDoctypeDeclHandler = _refuse
    checker.EntityDeclHandler = _refuse
    try:
        checker.Parse(data, True)
    except _Forbidden:
        raise InputFileError(
            path, f"line {checker.CurrentLineNumber}: DOCTYPE/ENTITY declarations are not accepted"
        ) from None
    except expat.ExpatError as e:
        raise InputFileError(
            path, f"malformed XML at line {e.lineno}, column {e.offset}: {expat.errors.messages[e.code]}"
        ) from None
    root = ET.fromstring(data)
    if root_tag is not None and root.tag != root_tag:
        raise InputFileError(path, f"root element is <{root.tag}>, expected <{root_tag}>")
    return root
