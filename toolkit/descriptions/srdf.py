"""An SRDF's planning groups and named states, read safely (the description's size limit,
Python's XML parser with its expansion limits): :func:`read_srdf`. What they mean for a
robot is :mod:`toolkit.robot.groups`'s."""

from __future__ import annotations

import os
import threading
import xml.etree.ElementTree as ET
from pathlib import Path

from ..errors import ModelLoadError
from .files import read_description

__all__ = ["Srdf", "read_srdf"]

Srdf = tuple[dict[str, ET.Element], list[ET.Element]]
"""An SRDF's ``<group>`` elements by name and its ``<group_state>`` elements."""


_READ: dict[tuple[str, int, int, int], Srdf] = {}
"""SRDFs read, by path and the file's inode, size and change time: a plan for a request's
group read its robot's SRDF twice (0.7 ms of a 10 ms plan); a file changed is read anew.
Callers only read what it holds."""
_LOCK = threading.Lock()


def read_srdf(path: Path | None) -> Srdf:
    """The groups and group states of the SRDF at ``path`` (none without one); read once
    while the file stays the same."""
    if path is None:
        return {}, []
    try:
        st = os.stat(path)
        key = (str(path), st.st_ino, st.st_size, st.st_mtime_ns)
    except OSError:
        key = None
    with _LOCK:
        found = _READ.get(key) if key is not None else None
    if found is not None:
        return found
    made = _read(Path(path))
    if key is not None:
        with _LOCK:
            if len(_READ) >= 64:
                _READ.clear()
            _READ[key] = made
    return made


def _read(path: Path) -> Srdf:
    """:func:`read_srdf` of the file, parsed."""
    text = read_description(path)
    try:
        root = ET.fromstring(text)
    except ET.ParseError as exc:
        raise ModelLoadError(f"{path}: not a readable SRDF ({exc})") from None
    groups = {str(g.get("name")): g for g in root.findall("group") if g.get("name")}
    return groups, root.findall("group_state")
