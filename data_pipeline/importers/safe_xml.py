"""Parsing untrusted XML (URDF, MJCF, ROS package.xml) through defusedxml."""

from __future__ import annotations

import xml.etree.ElementTree as ET
import xml.parsers.expat as expat
from pathlib import Path

import defusedxml
import defusedxml.ElementTree as DefusedET

from jax3dc.errors import InputFileError


def parse_xml(path: Path, root_tag: str | None = None) -> ET.Element:
    """Parse an untrusted URDF/MJCF file with defusedxml; every failure is one InputFileError line.

    Files come from datasets and the web, so any DOCTYPE is refused (``forbid_dtd``), and with it
    internal entities (billion laughs) and external ones (file disclosure). If ``root_tag`` is
    given, the root element must have it. The URDF and MJCF readers, the format sniffing and the
    ROS package lookup use it.
    """
    try:
        data = Path(path).read_bytes()
    except OSError as e:
        raise InputFileError(path, f"cannot read file: {e.strerror or e}") from None
    try:
        root = DefusedET.fromstring(data, forbid_dtd=True)
    except defusedxml.DefusedXmlException as e:
        raise InputFileError(path, f"DOCTYPE/ENTITY declarations are not accepted ({type(e).__name__})") from None
    except ET.ParseError as e:
        line, column = e.position
        raise InputFileError(
            path, f"malformed XML at line {line}, column {column}: {expat.ErrorString(e.code)}"
        ) from None
    if root_tag is not None and root.tag != root_tag:
        raise InputFileError(path, f"root element is <{root.tag}>, expected <{root_tag}>")
    return root
