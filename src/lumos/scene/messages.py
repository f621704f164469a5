"""Pydantic's validation errors as one line each: `<file>:<line>: <key path>: <what is wrong>`.

`format_validation_error` walks each error's location through the scene model's types (and the data) to the key
path a user wrote (`objects[2].radius`, `materials.red.kd`), finds its line in the file, and says what is wrong in
the words of `docs/scene-format.md`: the expected type or range, the allowed choices, a likely misspelling. Used
for scene files (`loader`), and for settings given in Python or on the command line.
"""

from __future__ import annotations

import difflib
import re
import types
from typing import Annotated, Any, Literal, Optional, Union, get_args, get_origin

from pydantic import BaseModel, Tag, ValidationError

from . import model as _model
from .model import MaterialError


def format_validation_error(
    exc: ValidationError,
    source: str,
    prefix: tuple = (),
    lines: Optional[dict] = None,
    data: Any = None,
) -> str:
    """One line for the first error of `exc`: `<source>[:<line>]: <key path>: <message> (and N more errors)`.

    `prefix` is prepended to every key path (settings validated on their own: `("render",)`); `lines` maps
    key paths (without the prefix) to line numbers; `data` is the validated input, used to tell pydantic's
    union tags from keys where the model types cannot.
    """
    root = getattr(_model, exc.title, None)
    errors = exc.errors(include_url=False)
    explained = [_explain(err, *_locate(err["loc"], root, data)) for err in errors]
    path, line_path, message, first = explained[0]
    text = f"{location(source, lines, line_path, prefix + path)}: {message}"
    others = {same for _, _, _, same in explained[1:]} - {first}  # a vector 2 short is one error, not 2
    if others:
        text += f" (and {len(others)} more error{'s' if len(others) > 1 else ''})"
    return text


def first_error(exc: ValidationError, data: Any = None) -> tuple[tuple, str]:
    """(key path, message) of the first error of `exc`, worded as `format_validation_error` words it (the key
    path relative to the validated model, e.g. ('position',) for a Camera)."""
    root = getattr(_model, exc.title, None)
    err = exc.errors(include_url=False)[0]
    path, _, message, _ = _explain(err, *_locate(err["loc"], root, data))
    return path, message


def format_path(path: tuple) -> str:
    """('objects', 2, 'radius') -> 'objects[2].radius'."""
    out = ""
    for part in path:
        if isinstance(part, int):
            out += f"[{part}]"
        elif isinstance(part, str) and re.fullmatch(r"[A-Za-z_][\w-]*", part):
            out += f".{part}" if out else part
        else:
            out += f"[{part!r}]"
    return out


def location(source: str, lines: Optional[dict], line_path: tuple, shown_path: Optional[tuple] = None) -> str:
    shown = format_path(line_path if shown_path is None else shown_path)
    line = _line(lines, line_path)
    head = f"{source}:{line}" if line is not None else source
    return f"{head}: {shown}" if shown else head


def _line(lines: Optional[dict], path: tuple) -> Optional[int]:
    """The line of `path`, or of its closest ancestor that has one."""
    if not lines:
        return None
    for n in range(len(path), -1, -1):
        if path[:n] in lines:
            return lines[path[:n]]
    return None


# --- walking pydantic's `loc` through the model types (and the data) -----------------------------------------

_NO_DATA = object()


def _locate(loc: tuple, root: Any, data: Any) -> tuple[list, list]:
    """Strip union tags from `loc`. Returns (key path, types) where types[k] is the type at path[:k]."""
    path, kinds = [], [root]
    tp, value = root, (_NO_DATA if data is None else data)
    for k, elem in enumerate(loc):
        member, is_tag = _enter_union(tp, elem)
        if is_tag:
            kinds[-1] = member if member is not None else kinds[-1]
            tp = member
            continue
        tp = member
        if elem == "[key]" or (tp is None and _looks_like_tag(value, elem, k == len(loc) - 1)):
            continue  # "[key]": pydantic's marker for an error in a dict key
        path.append(elem)
        tp, value = _child_type(tp, elem), _child_value(value, elem)
        kinds.append(tp)
    return path, kinds


def _unwrap(tp: Any) -> tuple[Any, Optional[str]]:
    """Annotated[X, Tag('t'), ...] -> (X, 't')."""
    tag = None
    while get_origin(tp) is Annotated:
        tp, *meta = get_args(tp)
        tag = next((m.tag for m in meta if isinstance(m, Tag)), tag)
    return tp, tag


def _is_union(tp: Any) -> bool:
    return get_origin(tp) in (Union, types.UnionType)


def _union_members(tp: Any) -> list[tuple[Any, list[str]]]:
    """(member type, its tags) of a union, None left out."""
    members = []
    for arg in get_args(tp):
        member, tag = _unwrap(arg)
        if member is not type(None):
            members.append((member, [tag] if tag else _literal_tags(member)))
    return members


def _literal_tags(tp: Any) -> list[str]:
    if isinstance(tp, type) and issubclass(tp, BaseModel) and "type" in tp.model_fields:
        annotation = tp.model_fields["type"].annotation
        if get_origin(annotation) is Literal:
            return [a for a in get_args(annotation) if isinstance(a, str)]
    return []


def _enter_union(tp: Any, elem: Any) -> tuple[Any, bool]:
    """At a union: (member, True) when `elem` is a member's tag; Optional[X] -> (X, False)."""
    tp, _ = _unwrap(tp)
    while _is_union(tp):
        members = _union_members(tp)
        if isinstance(elem, str):
            for member, tags in members:
                if elem in tags:
                    return member, True
        if len(members) == 1:
            tp = members[0][0]
            continue
        return None, isinstance(elem, str)  # pydantic names every member of a plain union in `loc`
    return tp, False


def _looks_like_tag(value: Any, elem: Any, last: bool) -> bool:
    if value is _NO_DATA or not isinstance(elem, str):
        return False
    return not (isinstance(value, dict) and (elem in value or last))


def _child_type(tp: Any, elem: Any) -> Any:
    tp, _ = _unwrap(tp)
    origin, args = get_origin(tp), get_args(tp)
    if isinstance(tp, type) and issubclass(tp, BaseModel):
        field = tp.model_fields.get(elem) if isinstance(elem, str) else None
        return field.annotation if field else None
    if origin is list and args:
        return args[0]
    if origin is dict and len(args) == 2:
        return args[1]
    if origin is tuple and args and isinstance(elem, int):
        if len(args) == 2 and args[1] is Ellipsis:
            return args[0]
        return args[elem] if elem < len(args) else None
    return None


def _child_value(value: Any, elem: Any) -> Any:
    if isinstance(value, dict):
        return value.get(elem, _NO_DATA)
    if isinstance(value, (list, tuple)) and isinstance(elem, int) and 0 <= elem < len(value):
        return value[elem]
    return _NO_DATA


def _candidates(tp: Any) -> list:
    """The types a value at `tp` may have: the members of a union, else `tp` itself (unwrapped)."""
    tp, _ = _unwrap(tp)
    return [member for member, _ in _union_members(tp)] if _is_union(tp) else [tp]


def _model_fields(tp: Any) -> list[str]:
    models = [c for c in _candidates(tp) if isinstance(c, type) and issubclass(c, BaseModel)]
    return list(models[0].model_fields) if len(models) == 1 else []


def _tuple_length(tp: Any) -> Optional[int]:
    """3 for a Vec3 (also inside Union[Vec3, float]); None when not a fixed-length tuple."""
    lengths = {len(get_args(c)) for c in _candidates(tp) if get_origin(c) is tuple and Ellipsis not in get_args(c)}
    return lengths.pop() if len(lengths) == 1 else None


# --- one friendly message per pydantic error type --------------------------------------------------------------

_EXPECTED = {
    "float_type": "a number",
    "int_type": "an integer",
    "bool_type": "true or false",
    "string_type": "a string",
    "list_type": "a list",
    "tuple_type": "a list",
    "dict_type": "a mapping",
    "model_type": "a mapping",
    "model_attributes_type": "a mapping",
}
_BOUNDS = {
    "greater_than": ("gt", "must be greater than"),
    "greater_than_equal": ("ge", "must be at least"),
    "less_than": ("lt", "must be less than"),
    "less_than_equal": ("le", "must be at most"),
}


def _explain(err: dict, path: list, kinds: list) -> tuple[tuple, tuple, str, tuple]:
    """(shown key path, key path whose line to report, message, identity) for one pydantic error.

    Errors with the same identity count as one (the missing components of one vector, the members of a union).
    """
    shown, line_path, message = _explain_one(err, tuple(path), kinds)
    identity = shown if line_path == shown else line_path
    return shown, line_path, message, identity


def _explain_one(err: dict, path: tuple, kinds: list) -> tuple[tuple, tuple, str]:
    kind, value, ctx = err["type"], err.get("input"), err.get("ctx") or {}
    if kind == "value_error" and isinstance(ctx.get("error"), MaterialError):
        where = ctx["error"].where
        return where, where, str(ctx["error"])
    if kind == "missing" and path and isinstance(path[-1], int):
        return path[:-1], path[:-1], _length_message(_tuple_length(kinds[-2]), value)
    if kind == "missing" and path:
        return path[:-1], path, f"missing required key '{path[-1]}'"
    if kind == "extra_forbidden" and path:
        return path[:-1], path, _unknown_key(path[-1], _model_fields(kinds[-2]))
    if kind in ("too_long", "too_short") and "actual_length" in ctx:
        expected = _tuple_length(kinds[-1]) or ctx.get("max_length") or ctx.get("min_length")
        return path, path, _length_message(expected, value, ctx["actual_length"])
    return path, path, _simple_message(kind, value, ctx, err["msg"], path, kinds[-1])


def _simple_message(kind: str, value: Any, ctx: dict, msg: str, path: tuple, tp: Any) -> str:
    if kind in _EXPECTED:
        expected = _EXPECTED[kind]
        n = _tuple_length(tp)
        if kind == "tuple_type" and n:
            expected = f"a list of {n} numbers" if n <= 4 else f"a list of {n} items"
        return f"expected {expected}, got {show(value)}"
    if kind == "finite_number":
        return "is NaN or infinite"
    if kind in _BOUNDS:
        key, words = _BOUNDS[kind]
        return f"{words} {_num(ctx.get(key))}, got {show(value, typed=False)}"
    if kind == "literal_error":
        return _choice_message("value", value, _quoted(ctx.get("expected", "")))
    if kind == "union_tag_invalid":
        tag = value.get("type", ctx.get("tag")) if isinstance(value, dict) else ctx.get("tag")
        return _choice_message(f"{_noun(path)} type", tag, _quoted(ctx.get("expected_tags", "")), "types:")
    if kind == "union_tag_not_found":
        return f"missing required key 'type' (types: {', '.join(_union_tags(tp))})"
    if kind == "light_type":
        return _light_type_message(value, _union_tags(tp))
    for lead in ("Value error, ", "Assertion failed, "):
        if msg.startswith(lead):
            return msg[len(lead):]
    return msg[:1].lower() + msg[1:]


def _length_message(expected: Optional[int], value: Any, actual: Optional[int] = None) -> str:
    items = list(value) if isinstance(value, (list, tuple)) else []
    actual = len(items) if actual is None else actual
    numbers = items and all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in items)
    noun = "components" if numbers else "items"
    return f"must have {expected} {noun}, got {actual}" if expected else f"has the wrong length ({actual})"


def _unknown_key(key: Any, fields: list[str]) -> str:
    match = difflib.get_close_matches(str(key), fields, n=1, cutoff=0.6)
    if match:
        return f"unknown key '{key}' (did you mean '{match[0]}'?)"
    return f"unknown key '{key}' (known keys: {', '.join(fields)})" if fields else f"unknown key '{key}'"


def _choice_message(what: str, value: Any, choices: list[str], label: str = "choose from") -> str:
    listed = f"{label} {', '.join(choices)}"
    shown = show(value, typed=not isinstance(value, str))
    match = difflib.get_close_matches(value, choices, n=1, cutoff=0.6) if isinstance(value, str) else []
    if match:
        return f"unknown {what} {shown} (did you mean '{match[0]}'? {listed})"
    return f"unknown {what} {shown} ({listed})"


def _light_type_message(value: Any, tags: list[str]) -> str:
    kinds = list(dict.fromkeys(t.split(".")[0] for t in tags))
    shapes = [t.split(".", 1)[1] for t in tags if "." in t]
    if not isinstance(value, dict):
        return f"expected a mapping, got {show(value)}"
    if "type" not in value:
        return f"missing required key 'type' (types: {', '.join(kinds)})"
    if value["type"] == "area" and "shape" not in value:
        return f"missing required key 'shape' (area light shapes: {', '.join(shapes)})"
    if value["type"] == "area":
        return _choice_message("area light shape", value["shape"], shapes, "shapes:")
    return _choice_message("light type", value["type"], kinds, "types:")


def _union_tags(tp: Any) -> list[str]:
    tp, _ = _unwrap(tp)
    return [tag for _, tags in _union_members(tp) for tag in tags] if _is_union(tp) else []


def _noun(path: tuple) -> str:
    if path[:1] == ("lights",):
        return "light"
    if path[:1] == ("objects",):
        return "object"
    keys = [p for p in path if isinstance(p, str)]
    return keys[-1] if keys else "object"


def _quoted(text: str) -> list[str]:
    return re.findall(r"'([^']*)'", text)


def _num(x: Any) -> str:
    if isinstance(x, float) and x.is_integer() and abs(x) < 1e15:
        return str(int(x))
    return f"{x:g}" if isinstance(x, float) else str(x)


def show(value: Any, typed: bool = True) -> str:
    """A short, YAML-flavoured rendering of an input value for messages."""
    if isinstance(value, dict):
        return "a mapping"
    if isinstance(value, (list, tuple)):
        return f"a list of {len(value)}"
    if value is None:
        return "nothing (null)"
    if isinstance(value, bool):
        text = "true" if value else "false"
    elif isinstance(value, str):
        text = repr(value if len(value) <= 40 else value[:37] + "...")
    else:
        text = one_line(repr(value))[:40]
    return f"{text} ({type(value).__name__})" if typed else text


def one_line(text: str) -> str:
    return " ".join(text.split())
