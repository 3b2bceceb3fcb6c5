"""CSV tables read as users write them (a header row, a byte-order mark, blank lines at the
end): the command line's inputs and :func:`toolkit.motion.read_csv`. Only a regular file of at
most :data:`MAX_CSV_BYTES` is read; a cell that is not a finite number is refused by row and
column."""

from __future__ import annotations

import csv
import io
import os
import stat
from pathlib import Path

import numpy as np

from ..errors import InvalidParameterError

__all__ = ["MAX_CSV_BYTES", "csv_column", "read_csv", "read_regular"]

MAX_CSV_BYTES = 64 * 1024 * 1024


def read_regular(path: str | Path, limit: int, what: str) -> bytes:
    """The bytes of ``path``, a regular file of at most ``limit`` bytes: opened without
    blocking (a FIFO or a device in the file's place is refused, not waited on or read
    forever); ``what`` names the file in the messages ("a scene", "a CSV table").
    FileNotFoundError and other OSErrors pass through for the caller to word."""
    if not isinstance(path, str | os.PathLike) or "\0" in os.fspath(path):
        raise InvalidParameterError(f"{what}: a file name (text, no NUL), got {path!r:.80}")
    fd = os.open(path, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0))
    with os.fdopen(fd, "rb") as handle:
        if not stat.S_ISREG(os.fstat(handle.fileno()).st_mode):
            raise InvalidParameterError(f"{path}: {what} is a regular file")
        raw = handle.read(limit + 1)
    if len(raw) > limit:
        raise InvalidParameterError(f"{path}: larger than {limit >> 20} MiB: not {what}")
    return raw


def read_csv(path: str | Path) -> tuple[list[str], list[list[str]]]:
    """(header, rows) of a CSV file with a header row and at least one data row."""
    try:
        raw = read_regular(path, MAX_CSV_BYTES, "a CSV table")
        # utf-8-sig: a byte-order mark (as spreadsheets write) is not part of the header
        text = raw.decode("utf-8-sig")
    except FileNotFoundError:
        raise InvalidParameterError(f"no such CSV file: {path}") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise InvalidParameterError(f"cannot read {path}: {exc}") from None
    rows = list(csv.reader(io.StringIO(text)))
    while rows and not any(cell.strip() for cell in rows[-1]):
        rows.pop()  # trailing blank lines
    if len(rows) < 2:
        raise InvalidParameterError(f"{path}: a header row and at least one data row needed")
    header = [h.strip() for h in rows[0]]
    for i, row in enumerate(rows[1:]):
        extra = [cell for cell in row[len(header) :] if cell.strip()]
        if extra:
            raise InvalidParameterError(
                f"{path}, row {i + 2}: {len(row)} cells, the header has {len(header)} "
                f"(extra: {', '.join(repr(c[:20]) for c in extra[:3])})"
            )
    return header, rows[1:]


def csv_column(rows: list[list[str]], k: int, name: str, path: str) -> np.ndarray:
    """Column ``k`` of ``rows`` as numbers (NaN where empty); a cell that is not a finite
    number is refused, naming its row and column."""
    out = np.full(len(rows), np.nan)
    for i, row in enumerate(rows):
        cell = row[k].strip() if k < len(row) else ""
        if cell:
            try:
                out[i] = float(cell)
            except ValueError:
                raise InvalidParameterError(
                    f"{path}, row {i + 2}, column {name!r}: not a number: {cell[:40]!r}"
                ) from None
            if not np.isfinite(out[i]):
                raise InvalidParameterError(f"{path}, row {i + 2}, column {name!r}: {cell!r}")
    return out
