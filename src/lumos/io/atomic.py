"""Output paths checked before any work, and whole-or-nothing file writes: every file lumos writes (images, sheets, radiosity solutions, baked meshes) is
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


def check_output_path(path: str | os.PathLike, extensions: tuple[str, ...], action: str) -> Path:
    """Check that a file could be written to `path` without writing anything; return it as a `Path`.

    extensions: the allowed suffixes, lower-case (matched case-insensitively).
    action: the start of the error message, e.g. 'cannot save radiosity solution'.
    Raises LumosError for a wrong extension, a directory, a folder that does not exist or is not writable.
    """
    out = Path(path)
    fail = f"{action} '{path}'"
    if out.is_dir():
        raise LumosError(f"{fail}: it is a directory")
    if out.suffix.lower() not in extensions:
        shown = f"extension '{out.suffix}'" if out.suffix else "no extension"
        raise LumosError(f"{fail}: unsupported {shown} (supported: {', '.join(extensions)})")
    folder = out.parent
    if not folder.exists():
        raise LumosError(f"{fail}: folder '{folder}' does not exist")
    if not folder.is_dir():
        raise LumosError(f"{fail}: '{folder}' is not a folder")
    if not os.access(folder, os.W_OK | os.X_OK):
        raise LumosError(f"{fail}: permission denied (folder '{folder}' is not writable)")
    return out
