"""pbrt-v4 scene files as statements: the tokenizer, the parameter lists and the stack of included files.

    stream = Statements(Path("scene.pbrt"))
    for st in stream:                      # Statement(directive, args, params, where)
        if st.directive == "Include":
            stream.include(st)             # the next statements come from the included file
        ...

The grammar is pbrt-v4's (src/pbrt/parser.cpp): a token is a quoted string (with the escapes \\b \\f \\n \\r \\t
\\\\ \\' \\"), `[`, `]`, a comment from `#` to the end of the line, or a bare word up to the next space, quote or
bracket. A statement is a directive (a bare word) followed by its fixed arguments (numbers or quoted strings, per
`DIRECTIVES`) and, for the directives that take one, a parameter list of `"type name" value` or
`"type name" [values]`. Every token keeps its file and line, so every error is one line
`<file>:<line>: <what>` (a LumosError): an unknown directive, a word where a number should be, a string that is
not closed, a `[` the file ends inside, a parameter type pbrt does not know, a value count that does not fit the
type, an included file that is missing or includes itself.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable, Iterator, Optional

import numpy as np

from ..errors import LumosError

#: what follows each directive: "" nothing, "nN" N numbers, "m16" 16 numbers in brackets, "s" a string,
#: "s12" one or two strings, "w" a bare word, "o" Option's name and value, "sP" a string and a parameter list,
#: "sssP" three strings and a parameter list
DIRECTIVES = {
    **dict.fromkeys(("AttributeBegin", "AttributeEnd", "Identity", "ReverseOrientation", "WorldBegin", "WorldEnd",
                     "ObjectEnd", "TransformBegin", "TransformEnd"), ""),
    "Translate": "n3", "Scale": "n3", "Rotate": "n4", "LookAt": "n9", "TransformTimes": "n2",
    "Transform": "m16", "ConcatTransform": "m16",
    **dict.fromkeys(("CoordinateSystem", "CoordSysTransform", "NamedMaterial", "ObjectBegin", "ObjectInstance",
                     "Include", "Import", "ColorSpace"), "s"),
    "MediumInterface": "s12", "ActiveTransform": "w", "Option": "o",
    **dict.fromkeys(("Camera", "Sampler", "Film", "PixelFilter", "Integrator", "Accelerator", "Shape", "Material",
                     "LightSource", "AreaLightSource", "MakeNamedMaterial", "MakeNamedMedium", "Attribute"), "sP"),
    "Texture": "sssP",
}
#: parameter types → how many numbers make one value (0: strings or booleans)
PARAM_TYPES = {"integer": 1, "float": 1, "point2": 2, "vector2": 2, "point3": 3, "vector3": 3, "normal3": 3,
               "normal": 3, "point": 3, "vector": 3, "color": 3, "rgb": 3, "blackbody": 1, "spectrum": 1,
               "bool": 0, "string": 0, "texture": 0}
_ALIASES = {"point": "point3", "vector": "vector3", "normal3": "normal", "color": "rgb"}
_NUMBER = re.compile(r"[+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?")
_NOT_NUMERIC = re.compile(r"[^0-9eE+\-.\s]")
_TOKEN = re.compile(r'\s+|#[^\n\r]*|"(?:[^"\\\n]|\\.)*"|\[|\]|[^\s"\[\]]+|"')
_ESCAPES = {"b": "\b", "f": "\f", "n": "\n", "r": "\r", "t": "\t", "\\": "\\", "'": "'", '"': '"'}
#: the deepest Include nesting (a guard besides the cycle check)
MAX_INCLUDE_DEPTH = 64


@dataclass(frozen=True)
class Where:
    """A place in a scene file, shown as `file:line`."""

    file: str
    line: int

    def __str__(self) -> str:
        return f"{self.file}:{self.line}"

    def error(self, what: str) -> LumosError:
        return LumosError(f"{self}: {what}")


@dataclass
class Param:
    """One `"type name" [values]` entry: values are floats, strings or booleans (integers as floats)."""

    type: str
    name: str
    values: list
    where: Where


@dataclass
class Statement:
    directive: str
    args: list
    params: dict[str, Param]
    where: Where
    path: Path  # the file the statement is in
    main_line: int  # its line in the main file, or that of the Include that brought it there


def tokenize(text: str, name: str) -> list[tuple[str, str, int]]:
    """The tokens of a pbrt file: (kind, text, line) with kind "word", "string" (dequoted), "[", "]" or "words"
    (the whole inside of a `[ ]` that holds no string or comment, unsplit: the numbers of a big mesh are converted
    at once); comments are dropped. `name` is the file as messages show it."""
    tokens: list[tuple[str, str, int]] = []
    line, pos, end_of_text = 1, 0, len(text)
    match = _TOKEN.match
    while pos < end_of_text:
        tok = match(text, pos).group()
        pos += len(tok)
        first = tok[0]
        if first.isspace():
            line += tok.count("\n")
        elif first == "#":
            continue
        elif first == '"':
            if len(tok) == 1 or tok[-1] != '"':
                raise LumosError(f"{name}:{line}: unterminated string")
            body = tok[1:-1]
            if "\\" in body:
                body = _unescape(body, f"{name}:{line}")
            tokens.append(("string", body, line))
        elif tok == "[":
            tokens.append(("[", "[", line))
            close = text.find("]", pos)
            inside = text[pos:close] if close >= 0 else ""
            if close >= 0 and '"' not in inside and "#" not in inside and "[" not in inside:
                if not inside.isspace() and inside:
                    tokens.append(("words", inside, line))
                line += inside.count("\n")
                pos = close
        elif tok == "]":
            tokens.append(("]", "]", line))
        else:
            tokens.append(("word", tok, line))
    return tokens


def split_words(inside: str, line: int) -> list[tuple[str, str, int]]:
    """A "words" token as "word" tokens, each with its own line."""
    return [("word", w, line + i) for i, text in enumerate(inside.split("\n")) for w in text.split()]


def _unescape(body: str, where: str) -> str:
    out, i = [], 0
    while i < len(body):
        ch = body[i]
        if ch == "\\":
            i += 1
            if body[i] not in _ESCAPES:
                raise LumosError(f"{where}: unexpected escaped character '\\{body[i]}' in a string")
            ch = _ESCAPES[body[i]]
        out.append(ch)
        i += 1
    return "".join(out)


def number(text: str, where: Where) -> float:
    """A bare word read as a number (pbrt's syntax: no nan, inf, hex or underscores)."""
    if not _NUMBER.fullmatch(text):
        raise where.error(f"expected a number, got '{text}'")
    return float(text)


class _File:
    """An open file of the stack: its tokens and the position reached."""

    def __init__(self, path: Path, name: str, tokens: list, on_end: Optional[Callable[[], None]],
                 entry: Optional[int]):
        self.path, self.name, self.tokens, self.pos, self.on_end = path, name, tokens, 0, on_end
        self.pending: list = []  # the words of a "words" token being read one by one, last first
        self.entry = entry  # the line of the main file's Include that this file came through (None: the main file)


class Statements:
    """The statements of a pbrt file and of the files it includes, in order (an iterator)."""

    def __init__(self, path: Path):
        self.main = path
        self._stack: list[_File] = []
        self._open(path, str(path), None, None)

    # ---- files

    def _open(self, path: Path, name: str, on_end: Optional[Callable[[], None]], entry: Optional[int]) -> None:
        try:
            raw = path.read_bytes()
        except OSError as exc:
            raise LumosError(f"{name}: cannot read it ({exc.strerror or exc})") from None
        if raw[:2] in (b"\xfe\xff", b"\xff\xfe"):
            raise LumosError(f"{name}:1: the file is UTF-16; pbrt scene files are UTF-8 text")
        if path.suffix.lower() == ".gz" or raw[:2] == b"\x1f\x8b":
            import gzip

            try:
                raw = gzip.decompress(raw)
            except (OSError, EOFError) as exc:
                raise LumosError(f"{name}: not a readable gzip file ({exc})") from None
        text = raw.decode("utf-8-sig", errors="replace")
        self._stack.append(_File(path, name, tokenize(text, name), on_end, entry))

    def include(self, st: Statement, on_end: Optional[Callable[[], None]] = None) -> None:
        """Continue with the file named by an Include or Import statement; `on_end` is called when it ends.

        The name is resolved as pbrt does, relative to the main file's folder (pbrt's search directory), and,
        when no such file is there, relative to the including file's folder."""
        given = st.args[0]
        candidates = [self.main.parent / given, st.path.parent / given]
        path = next((p for p in candidates if p.is_file()), None)
        if path is None:
            raise st.where.error(f"{st.directive}: no such file '{given}'")
        resolved = path.resolve()
        for f in self._stack:
            if f.path.resolve() == resolved:
                raise st.where.error(f"{st.directive} '{given}': the file includes itself (a cycle through "
                                     f"{' → '.join(g.name for g in self._stack)})")
        if len(self._stack) >= MAX_INCLUDE_DEPTH:
            raise st.where.error(f"{st.directive}: files included more than {MAX_INCLUDE_DEPTH} deep")
        self._open(path, str(path), on_end, st.main_line)

    # ---- tokens

    def _next(self, required: Optional[str] = None, raw: bool = False):
        """The next token of the current file, or None at its end (an error when `required` says what for); a
        "words" token is split into words unless `raw`."""
        top = self._stack[-1]
        if top.pending:
            return top.pending.pop()
        if top.pos < len(top.tokens):
            top.pos += 1
            tok = top.tokens[top.pos - 1]
            if tok[0] == "words" and not raw:
                top.pending = split_words(tok[1], tok[2])[::-1]
                return top.pending.pop()
            return tok
        if required:
            line = top.tokens[-1][2] if top.tokens else 1
            raise LumosError(f"{top.name}:{line}: the file ends before {required}")
        return None

    def _peek(self):
        top = self._stack[-1]
        if top.pending:
            return top.pending[-1]
        return top.tokens[top.pos] if top.pos < len(top.tokens) else None

    def __iter__(self) -> Iterator[Statement]:
        return self

    def __next__(self) -> Statement:
        while self._stack and self._peek() is None:
            done = self._stack.pop()
            if done.on_end is not None:
                done.on_end()
        if not self._stack:
            raise StopIteration
        top = self._stack[-1]
        kind, text, line = self._next()
        where = Where(top.name, line)
        if kind != "word":
            shown = f'"{text}"' if kind == "string" else text
            raise where.error(f"expected a directive, got {shown}")
        if text not in DIRECTIVES:
            raise where.error(f"unknown directive '{text}'")
        args = self._arguments(text, DIRECTIVES[text], where)
        params = self._params(text) if DIRECTIVES[text].endswith("P") else {}
        return Statement(text, args, params, where, top.path, line if top.entry is None else top.entry)

    def _arguments(self, directive: str, shape: str, where: Where) -> list:
        if not shape:
            return []
        if shape.startswith("n"):
            count = int(shape[1:])
            return [self._number(f"the {count} numbers of {directive}", where) for _ in range(count)]
        if shape == "m16":
            bracket = self._peek()
            if bracket is not None and bracket[0] == "[":
                self._next()
            values = [self._number(f"the 16 numbers of {directive}", where) for _ in range(16)]
            if bracket is not None and bracket[0] == "[":
                kind, text, line = self._next(f"the ']' of {directive}")
                if kind != "]":
                    raise Where(where.file, line).error(f"{directive} takes 16 numbers, then ']'")
            return values
        if shape == "w":
            kind, text, line = self._next(f"the argument of {directive}")
            return [text]
        if shape == "o":
            name = self._string(f"the name of {directive}", where)
            return [name, self._next(f"the value of {directive}")[1]]
        count = {"s": 1, "s12": 1, "sP": 1, "sssP": 3}[shape]
        args = [self._string(f"the {'name' if count == 1 else 'names'} after {directive}", where)
                for _ in range(count)]
        if shape == "s12" and self._peek() is not None and self._peek()[0] == "string":
            args.append(self._next()[1])
        return args

    def _number(self, what: str, where: Where) -> float:
        kind, text, line = self._next(what)
        if kind != "word":
            raise Where(where.file, line).error(f"expected a number ({what}), got {_shown(kind, text)}")
        return number(text, Where(where.file, line))

    def _string(self, what: str, where: Where) -> str:
        kind, text, line = self._next(what)
        if kind != "string":
            raise Where(where.file, line).error(f"expected a quoted string ({what}), got {_shown(kind, text)}")
        return text

    def _params(self, directive: str) -> dict[str, Param]:
        params: dict[str, Param] = {}
        while (tok := self._peek()) is not None and tok[0] == "string":
            self._next()
            param = self._param(tok[1], Where(self._stack[-1].name, tok[2]), directive)
            params[param.name] = param  # pbrt: a repeated name, the last one counts
        return params

    def _param(self, decl: str, where: Where, directive: str) -> Param:
        parts = decl.split()
        if len(parts) != 2:
            raise where.error(f'"{decl}": a parameter is declared as "type name" ({directive})')
        kind, name = parts
        if kind not in PARAM_TYPES:
            raise where.error(f'"{decl}": unknown parameter type \'{kind}\' (types: {", ".join(PARAM_TYPES)})')
        kind = _ALIASES.get(kind, kind)
        values = self._values(decl, where)
        return Param(kind, name, _typed(kind, decl, values, where), where)

    def _values(self, decl: str, where: Where) -> list[tuple[str, str, int]]:
        tok = self._next(f'the value of "{decl}"')
        if tok[0] != "[":
            if tok[0] == "]":
                raise Where(where.file, tok[2]).error(f'"{decl}": \']\' without \'[\'')
            return [tok]
        values = []
        while True:
            top = self._stack[-1]
            if top.pos >= len(top.tokens) and not top.pending:
                raise Where(where.file, tok[2]).error(f'"{decl}": the file ends inside its [ ] (the \'[\' is '
                                                      f'never closed)')
            item = self._next(raw=True)
            if item[0] == "]":
                return values
            if item[0] == "[":
                raise Where(where.file, item[2]).error(f'"{decl}": \'[\' inside its [ ]')
            values.append(item)


def _shown(kind: str, text: str) -> str:
    return f'"{text}"' if kind == "string" else (f"'{text}'" if kind == "word" else text)


def _typed(kind: str, decl: str, tokens: list, where: Where) -> list:
    """The values of a parameter, checked against its type."""
    if PARAM_TYPES[kind] and len(tokens) == 1 and tokens[0][0] == "words":
        values = _all_numbers(tokens[0][1])  # all at once: a mesh's millions of numbers
        if values is not None and (kind != "integer" or np.array_equal(values, np.round(values))):
            return _counted(kind, decl, values.tolist(), where)
    tokens = [w for t in tokens for w in (split_words(t[1], t[2]) if t[0] == "words" else [t])]
    if kind in ("string", "texture"):
        for t in tokens:
            if t[0] != "string":
                raise Where(where.file, t[2]).error(f'"{decl}": expected quoted strings, got {_shown(t[0], t[1])}')
        return [t[1] for t in tokens]
    if kind == "bool":
        out = []
        for t in tokens:
            if t[1] not in ("true", "false"):
                raise Where(where.file, t[2]).error(f'"{decl}": expected true or false, got {_shown(t[0], t[1])}')
            out.append(t[1] == "true")
        return out
    if kind == "spectrum" and len(tokens) == 1 and tokens[0][0] == "string":
        return [tokens[0][1]]  # a named spectrum or a file of (λ, value) pairs
    out = []
    for t in tokens:
        if t[0] != "word":
            raise Where(where.file, t[2]).error(f'"{decl}": expected numbers, got {_shown(t[0], t[1])}')
        value = number(t[1], Where(where.file, t[2]))
        if kind == "integer" and not value.is_integer():
            raise Where(where.file, t[2]).error(f'"{decl}": expected integers, got {t[1]}')
        out.append(value)
    return _counted(kind, decl, out, where)


def _all_numbers(inside: str) -> Optional[np.ndarray]:
    """The numbers of a `[ ]`, or None when one of them is not a number in pbrt's syntax (the slow path then says
    which): only digits, signs, points and exponents, each word a float."""
    if _NOT_NUMERIC.search(inside):
        return None
    try:
        return np.array(inside.split(), dtype=np.float64)
    except ValueError:
        return None


def _counted(kind: str, decl: str, out: list, where: Where) -> list:
    size = 2 if kind == "spectrum" else PARAM_TYPES[kind]
    if size > 1 and len(out) % size:
        what = "(wavelength, value) pairs" if kind == "spectrum" else f"a multiple of {size} numbers"
        raise where.error(f'"{decl}": expected {what}, got {len(out)} numbers')
    return out


@dataclass
class Params:
    """Typed access to a statement's parameter list; remembers which parameters were read, so that the rest can
    be reported (pbrt stops at a parameter it does not use; lumos warns)."""

    params: dict[str, Param]
    where: Where
    used: set = field(default_factory=set)

    def get(self, name: str, *types: str) -> Optional[Param]:
        """The parameter `name` if it is there (of one of `types`, when given), marking it used."""
        p = self.params.get(name)
        if p is None:
            return None
        self.used.add(name)
        if types and p.type not in types:
            raise p.where.error(f'"{p.type} {name}": expected {" or ".join(types)}')
        return p

    def has(self, name: str) -> bool:
        return name in self.params

    def ignore(self, *names: str) -> None:
        self.used.update(names)

    def unused(self) -> list[Param]:
        return [p for name, p in self.params.items() if name not in self.used]

    def _values(self, name: str, types: tuple, count: Optional[int]) -> Optional[list]:
        p = self.get(name, *types)
        if p is None:
            return None
        if count is not None and len(p.values) != count:
            raise p.where.error(f'"{p.type} {name}": expected {count} value{"s" if count > 1 else ""}, '
                                f'got {len(p.values)}')
        return p.values

    def float(self, name: str, default: float) -> float:
        values = self._values(name, ("float", "integer"), 1)
        return default if values is None else float(values[0])

    def int(self, name: str, default: int) -> int:
        values = self._values(name, ("integer",), 1)
        return default if values is None else int(values[0])

    def bool(self, name: str, default: bool) -> bool:
        values = self._values(name, ("bool",), 1)
        return default if values is None else bool(values[0])

    def string(self, name: str, default: Optional[str]) -> Optional[str]:
        values = self._values(name, ("string",), 1)
        return default if values is None else values[0]

    def floats(self, name: str, *types: str) -> Optional[list]:
        return self._values(name, types or ("float",), None)

    def point(self, name: str, default) -> tuple:
        values = self._values(name, ("point3", "vector3", "normal"), 3)
        return tuple(default) if values is None else tuple(values)


class Warnings:
    """LumosWarnings said once per key (a directive, a plugin, a parameter): `<file>:<line>: <what>`."""

    def __init__(self):
        self.seen: set = set()

    def once(self, key, where: Where, what: str) -> None:
        if key in self.seen:
            return
        self.seen.add(key)
        import warnings

        from ..errors import LumosWarning

        warnings.warn(LumosWarning(f"{where}: {what}"), stacklevel=2)
