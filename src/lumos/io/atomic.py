"""Whole-or-nothing file writes: every file lumos writes (images, sheets, radiosity solutions, baked meshes) is
written to a temporary file beside its destination and moved over it only once complete, so an interrupted or
failed write leaves the old file (or none), never half a file."""

from __future__ import annotations

import os
import tempfile
from pathlib import Path
from typing import Callable, Optional

from ..errors import LumosError


def one_line(exc: BaseException) -> str:
    """An exception's message squeezed onto one short line."""
    text = " ".join(str(exc).split()) or type(exc).__name__
    return text if len(text) <= 160 else text[:157] + "..."


def write_atomically(out: Path, write: Callable[[str], None], fail: str, suffix: Optional[str] = None) -> None:
    """Run `write(tmp_name)` on a temporary file beside `out` (named with `suffix`, default `out`'s own, for
    writers that pick the format from the name), then move it over `out`; on any failure remove the temporary
    file and leave `out` as it was. OSErrors become LumosError `'{fail}: <reason>'`."""
    out = Path(out)
    try:
        with tempfile.NamedTemporaryFile(dir=out.parent, prefix=f".{out.name}.",
                                         suffix=out.suffix if suffix is None else suffix, delete=False) as f:
            tmp = f.name
    except OSError as exc:
        raise LumosError(f"{fail}: {one_line(exc)}") from None
    try:
        write(tmp)
        os.chmod(tmp, final_mode(out))  # NamedTemporaryFile is 0600; give the usual permissions
        os.replace(tmp, out)
    except BaseException as exc:
        try:
            os.unlink(tmp)
        except OSError:
            pass
        if isinstance(exc, OSError):
            raise LumosError(f"{fail}: {one_line(exc)}") from None
        raise


def final_mode(out: Path) -> int:
    """The permission bits `out` should get: those of the file it replaces, else 0666 less the umask."""
    try:
        return out.stat().st_mode & 0o777
    except OSError:
        umask = os.umask(0)
        os.umask(umask)
        return 0o666 & ~umask
