"""An SRDF's planning groups and named states, read safely (the description's size limit,
Python's XML parser with its expansion limits): :func:`read_srdf`. What they mean for a
robot is :mod:`toolkit.robot.groups`'s."""

from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path

from ..errors import ModelLoadError
from .files import read_description

__all__ = ["Srdf", "read_srdf"]

Srdf = tuple[dict[str, ET.Element], list[ET.Element]]
"""An SRDF's ``<group>`` elements by name and its ``<group_state>`` elements."""


def read_srdf(path: Path | None) -> Srdf:
    """The groups and group states of the SRDF at ``path`` (none without one)."""
    if path is None:
        return {}, []
    text = read_description(Path(path))
    try:
        root = ET.fromstring(text)
    except ET.ParseError as exc:
        raise ModelLoadError(f"{path}: not a readable SRDF ({exc})") from None
    groups = {str(g.get("name")): g for g in root.findall("group") if g.get("name")}
    return groups, root.findall("group_state")
