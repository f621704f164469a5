"""Lines of the Wavefront text formats (OBJ, MTL): decoded, comments cut, `\\` continuations joined."""

from __future__ import annotations


def logical_lines(data: bytes) -> tuple[list[tuple[int, str]], bool]:
    """The non-empty statements of a Wavefront text file and whether it used CRLF line ends.

    data: the file's bytes (UTF-8, or Latin-1 where it is not valid UTF-8).
    Returns ([(line number, text)], crlf): the text of each statement with its comment (from '#') removed,
    tabs read as spaces, and lines ending in a backslash joined to the next (numbered by their first line).
    """
    try:
        text = data.decode("utf-8-sig")
    except UnicodeDecodeError:
        text = data.decode("latin-1")
    crlf = "\r\n" in text
    if crlf or "\r" in text:
        text = text.replace("\r\n", "\n").replace("\r", "\n")
    out: list[tuple[int, str]] = []
    pending, start = "", 0
    for number, line in enumerate(text.split("\n"), 1):
        if "#" in line:
            line = line[:line.index("#")]
        if line.endswith("\\"):
            if not pending:
                start = number
            pending += line[:-1] + " "
            continue
        if pending:
            line, number, pending = pending + line, start, ""
        if line and not line.isspace():
            out.append((number, line))
    if pending and not pending.isspace():
        out.append((start, pending))
    return out, crlf
