"""Mitsuba 3 scene XML → a tree of plugin nodes: the reading half of `lumos.io.mitsuba`.

    root = parse_scene(Path("scene.xml"))       # the <scene> Node, includes spliced in and refs resolved
    root.objects                                # [(property name or None, Node)], in document order
    node.float("radius", 1.0), node.color_value("reflectance"), node.transform("to_world")   # typed access

What is read, as Mitsuba 3's own parser reads it (`src/core/parser.cpp`):
- `<scene version=...>` (required); a file older than 2.0.0 has its camelCase property names turned into
  snake_case (`intIOR` → `int_ior`, `toWorld` → `to_world`), `diffuse_reflectance` of a `diffuse` renamed
  `reflectance`, and `uoffset`/`voffset`/`uscale`/`vscale` made a `to_uv` transform, as Mitsuba upgrades them.
- `<default name value>` and `$name` in any attribute (longest names first; `\\$` is a dollar sign); a default
  never overrides a value given to `parse_scene(params=...)`. An undefined `$name` is an error.
- `<include filename>` (relative to the including file's folder first, then the main file's): an included
  `<scene>` adds its children, another root element is added as one object. Includes may not form a cycle.
- objects: `<shape>`, `<bsdf>`, `<texture>`, `<emitter>`, `<sensor>`, `<film>`, `<rfilter>`, `<sampler>`,
  `<integrator>`, `<medium>`, `<phase>`, `<volume>`, `<spectrum type=...>`; `id`s, `<ref id [name]>` (to an id
  defined anywhere in the scene; a ref that leads back to itself is an error) and `<alias id as>`.
- values: `<float>`, `<integer>`, `<boolean>`, `<string>`, `<rgb>` (1 or 3 numbers, commas or spaces),
  `<spectrum>` (one value, wavelength:value pairs, or an `.spd` file), `<point>`/`<vector>` (value or x/y/z).
- `<transform name>` of `translate`, `rotate`, `scale`, `matrix` (16 or 9 numbers) and `lookat`, each op
  left-multiplying what came before (M = op · M), in document order.

Every problem is a LumosError `<file>:<line>: <what>` (the file where the element is, which for an included
element is the included file).
"""

from __future__ import annotations

import re
import xml.parsers.expat
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Optional, Union

import numpy as np

from ..errors import LumosError
from .mitsuba_data import read_spd
from .mitsuba_values import SPLIT, TRANSFORM_OPS, Where, number, numbers, required, transform_op, xyz

OBJECT_TAGS = {"scene", "shape", "bsdf", "texture", "emitter", "sensor", "film", "rfilter", "sampler",
               "integrator", "medium", "phase", "volume"}
VALUE_TAGS = {"float", "integer", "boolean", "string", "rgb", "spectrum", "point", "vector"}
MAX_INCLUDE_DEPTH = 32
_INTEGER = re.compile(r"[+-]?\d+")
_PARAM = re.compile(r"(?<!\\)\$([A-Za-z0-9_]*)")


# ------------------------------------------------------------------------------------------------ the model


@dataclass
class Value:
    """A property value: kind is the tag (`float`, `integer`, `boolean`, `string`, `rgb`, `spectrum`, `point`,
    `vector`, `transform`); value is a float, int, bool, str, an RGB tuple, a Spectrum, a float64 (3,) array or a
    float64 (4, 4) matrix."""

    kind: str
    value: Any
    where: Where


@dataclass(frozen=True)
class Spectrum:
    """A `<spectrum>`: uniform (`wavelengths` empty, one value) or piecewise linear over increasing wavelengths."""

    wavelengths: tuple
    values: tuple


@dataclass
class Ref:
    """A `<ref id>` until the whole scene is read (ids may be defined after they are used)."""

    id: str
    where: Where


@dataclass(eq=False)
class Node:
    """One Mitsuba object element (`<shape type="sphere">`…). `props` maps property names to Values and named
    child objects; `objects` lists every child object (named or not) in document order with its name."""

    tag: str
    type: str
    id: Optional[str]
    where: Where
    props: dict[str, Union[Value, "Node"]] = field(default_factory=dict)
    objects: list[tuple[Optional[str], "Node"]] = field(default_factory=list)
    #: the root's `<path>` folders, where files are looked for after the element's own folder and the main file's
    folders: list = field(default_factory=list)

    def label(self) -> str:
        return f"{self.tag} '{self.type}'" + (f" (id '{self.id}')" if self.id else "")

    # ---- typed access: each raises `<file>:<line>: <tag> '<type>': <name>: ...` on a value of the wrong kind

    def value(self, name: str, kinds: tuple, what: str) -> Optional[Value]:
        item = self.props.get(name)
        if item is None:
            return None
        if isinstance(item, Node) or item.kind not in kinds:
            got = f"<{item.tag} type='{item.type}'>" if isinstance(item, Node) else f"<{item.kind}>"
            where = item.where if isinstance(item, (Node, Value)) else self.where
            raise where.error(f"{self.label()}: '{name}' must be {what}, got {got}")
        return item

    def float(self, name: str, default: Optional[float] = None) -> Optional[float]:
        item = self.value(name, ("float", "integer"), "a number (<float>)")
        return default if item is None else float(item.value)

    def int(self, name: str, default: Optional[int] = None) -> Optional[int]:
        item = self.value(name, ("integer",), "an <integer>")
        return default if item is None else item.value

    def bool(self, name: str, default: bool = False) -> bool:
        item = self.value(name, ("boolean",), "a <boolean>")
        return default if item is None else item.value

    def string(self, name: str, default: Optional[str] = None) -> Optional[str]:
        item = self.value(name, ("string",), "a <string>")
        return default if item is None else item.value

    def vector(self, name: str, default=None) -> Optional[np.ndarray]:
        item = self.value(name, ("point", "vector"), "a <point> or <vector>")
        return (None if default is None else np.asarray(default, np.float64)) if item is None else item.value

    def transform(self, name: str = "to_world") -> np.ndarray:
        """The named `<transform>` as a 4×4 float64 matrix (the identity when absent)."""
        item = self.value(name, ("transform",), "a <transform>")
        return np.eye(4) if item is None else item.value

    def children(self, tag: str) -> list[tuple[Optional[str], "Node"]]:
        """The child objects with this tag (named or not), in document order."""
        return [(name, node) for name, node in self.objects if node.tag == tag]

    def where_of(self, name: str) -> Where:
        item = self.props.get(name)
        return item.where if isinstance(item, (Node, Value)) else self.where


# ------------------------------------------------------------------------------------------------ entry point


def parse_scene(path: Path, params: Optional[dict] = None) -> Node:
    """Read the Mitsuba scene file `path` (with its includes) into its root `<scene>` Node, refs resolved.

    params: values for `$name` parameters (as `mitsuba -Dname=value`), which `<default>`s do not override."""
    reader = _Reader(path, {k: str(v) for k, v in (params or {}).items()})
    try:
        root = reader.read_file(path, None, ())
    except RecursionError:
        raise LumosError(f"{path}: elements nested too deeply") from None
    if root.tag != "scene":
        raise root.where.error(f"the root element must be <scene>, not <{root.tag}>")
    root.folders = reader.folders
    try:
        _resolve_refs(root, reader.ids)
    except RecursionError:
        raise LumosError(f"{path}: objects nested too deeply") from None
    return root


class _Element:
    """An XML element as expat saw it: tag, attributes, child elements, 1-based line."""

    __slots__ = ("tag", "attrs", "children", "line")

    def __init__(self, tag: str, attrs: dict, line: int):
        self.tag, self.attrs, self.children, self.line = tag, attrs, [], line


def read_xml(path: Path, shown: str) -> _Element:
    """The root element of an XML file, with line numbers; a LumosError `<shown>:<line>: invalid XML: ...`."""
    try:
        raw = path.read_bytes()
    except OSError as exc:
        raise LumosError(f"{shown}: cannot read: {exc.strerror or exc}") from None
    parser = xml.parsers.expat.ParserCreate()
    stack: list[_Element] = []
    root: list[_Element] = []

    def start(tag, attrs):
        element = _Element(tag, attrs, parser.CurrentLineNumber)
        (stack[-1].children if stack else root).append(element)
        stack.append(element)

    def refuse_entities(name, *_):  # no DTD entities: they are how "billion laughs" files blow up
        raise LumosError(f"{shown}:{parser.CurrentLineNumber}: invalid XML: entity declarations are not read "
                         f"(<!ENTITY {name}>)")

    parser.StartElementHandler = start
    parser.EndElementHandler = lambda tag: stack.pop()
    parser.EntityDeclHandler = refuse_entities
    try:
        parser.Parse(raw, True)
    except xml.parsers.expat.ExpatError as exc:
        what = xml.parsers.expat.ErrorString(exc.code)
        raise LumosError(f"{shown}:{exc.lineno}: invalid XML: {what} (column {exc.offset + 1})") from None
    return root[0]


# ------------------------------------------------------------------------------------------------ the reader


class _Reader:
    """Reads one file after another (includes), sharing the parameters, the ids and the main file's folder."""

    def __init__(self, main: Path, params: dict[str, str]):
        self.main = main
        self.params = dict(params)
        self.ids: dict[str, Node] = {}
        self.folders: list[Path] = []  # <path> folders, searched after the file's own and the main file's

    def read_file(self, path: Path, top: Optional[int], chain: tuple) -> Node:
        """Parse `path` (top: the line of the include in the main file; chain: the files including it)."""
        root = read_xml(path, str(path))
        where = Where(path, root.line, root.line if top is None else top)
        version = root.attrs.get("version")
        if version is None:
            raise where.error(f"<{root.tag}> needs a version attribute (Mitsuba 3 files start "
                              f"<scene version=\"3.0.0\">)")
        try:
            numbers = tuple(int(p) for p in self.substitute(version, where).split("."))
        except ValueError:
            raise where.error(f"invalid version number '{version}'") from None
        file = _File(path, top, chain + (path.resolve(),), numbers < (2, 0, 0))
        if root.tag not in OBJECT_TAGS:
            raise where.error(f"the root element must be <scene> or another object, not <{root.tag}>")
        return self.object(root, file)

    def where(self, element: _Element, file: "_File") -> Where:
        return Where(file.path, element.line, element.line if file.top is None else file.top)

    def substitute(self, text: str, where: Where) -> str:
        """`$name` replaced by its parameter (longest names first); `\\$` stays a dollar sign."""
        if "$" not in text:
            return text
        for name in sorted(self.params, key=len, reverse=True):
            text = re.sub(r"(?<!\\)\$" + re.escape(name), lambda _m, v=self.params[name]: v, text)
        left = _PARAM.search(text)
        if left:
            raise where.error(f"undefined parameter ${left.group(1)} (give it a <default name=\"{left.group(1)}\" "
                              f"value=\"...\"/>)")
        return text.replace("\\$", "$")

    def attrs(self, element: _Element, where: Where) -> dict[str, str]:
        return {k: self.substitute(v, where) for k, v in element.attrs.items()}

    # ---- elements

    def object(self, element: _Element, file: "_File") -> Node:
        where = self.where(element, file)
        attrs = self.attrs(element, where)
        tag = element.tag
        if tag != "scene" and "type" not in attrs:
            raise where.error(f"<{tag}> needs a type attribute")
        node = Node("texture" if tag == "spectrum" else tag, attrs.get("type", "scene"), attrs.get("id"), where)
        for child in element.children:
            self.child(node, child, file)
        if file.old:
            _upgrade_v1(node)
        if node.id is not None:
            if node.id in self.ids:
                raise where.error(f"duplicate id '{node.id}' (first at {self.ids[node.id].where})")
            self.ids[node.id] = node
        return node

    def child(self, parent: Node, element: _Element, file: "_File") -> None:
        where = self.where(element, file)
        tag = element.tag
        if tag in OBJECT_TAGS or (tag == "spectrum" and "type" in element.attrs):
            child = self.object(element, file)
            name = element.attrs.get("name")
            self.add(parent, None if name is None else self.substitute(name, where), child, where, file)
            return
        attrs = self.attrs(element, where)
        if tag not in ("transform",) and element.children:
            raise where.error(f"<{element.children[0].tag}> cannot be inside <{tag}>")
        if tag in VALUE_TAGS:
            name = required(attrs, "name", tag, where)
            self.add(parent, name, Value(tag, self.parse_value(tag, attrs, where, file), where), where, file)
        elif tag == "transform":
            name = required(attrs, "name", tag, where)
            self.add(parent, name, Value("transform", self.parse_transform(element, file), where), where, file)
        elif tag == "ref":
            ref = Ref(required(attrs, "id", tag, where), where)
            self.add(parent, attrs.get("name"), ref, where, file)
        elif tag == "include":
            self.include(parent, attrs, where, file)
        elif tag == "default":
            name, value = required(attrs, "name", tag, where), required(attrs, "value", tag, where)
            self.params.setdefault(name, value)
        elif tag == "alias":
            source, alias = required(attrs, "id", tag, where), required(attrs, "as", tag, where)
            if source not in self.ids:
                raise where.error(f"<alias>: no object has id '{source}' (yet)")
            self.ids[alias] = self.ids[source]
        elif tag == "path":
            folder = Path(required(attrs, "value", tag, where)).expanduser()  # a folder to look for files in
            self.folders.append(folder if folder.is_absolute() else file.path.parent / folder)
        elif tag in TRANSFORM_OPS:
            raise where.error(f"<{tag}> can only appear inside a <transform>")
        else:
            raise where.error(f"unknown XML element <{tag}> (Mitsuba 3 has no such tag)")

    def add(self, parent: Node, name: Optional[str], item, where: Where, file: "_File") -> None:
        if name is not None and file.old:
            name = camel_to_snake(name)
        if name is not None:
            if name in parent.props:
                raise where.error(f"{parent.label()}: '{name}' is given twice")
            parent.props[name] = item
        if isinstance(item, (Node, Ref)):
            parent.objects.append((name, item))

    def include(self, parent: Node, attrs: dict, where: Where, file: "_File") -> None:
        name = required(attrs, "filename", "include", where)
        path = file.resolve(name, self.main, self.folders)
        if path is None:
            raise where.error(f"included file '{name}' not found")
        if path.resolve() in file.chain:
            cycle = " -> ".join(p.name for p in file.chain + (path.resolve(),))
            raise where.error(f"<include> cycle: {cycle}")
        if len(file.chain) >= MAX_INCLUDE_DEPTH:
            raise where.error(f"<include>s nested more than {MAX_INCLUDE_DEPTH} deep")
        root = self.read_file(path, where.top, file.chain)
        if root.tag == "scene":
            for key, item in root.props.items():
                if key in parent.props:
                    raise where.error(f"{parent.label()}: '{key}' is given twice (again in {path.name})")
                parent.props[key] = item
            parent.objects.extend(root.objects)
        else:
            self.add(parent, attrs.get("name"), root, where, file)

    # ---- values

    def parse_value(self, tag: str, attrs: dict, where: Where, file: "_File"):
        if tag in ("point", "vector"):
            return xyz(attrs, where, 0.0, tag)
        if tag == "spectrum":
            return self.parse_spectrum(attrs, where, file)
        text = required(attrs, "value", tag, where)
        if tag == "float":
            return number(text, where)
        if tag == "integer":
            if not _INTEGER.fullmatch(text.strip()):
                raise where.error(f"<integer>: '{text}' is not an integer")
            return int(text)
        if tag == "boolean":
            if text.strip().lower() not in ("true", "false"):
                raise where.error(f"<boolean>: '{text}' is neither true nor false")
            return text.strip().lower() == "true"
        if tag == "rgb":
            values = numbers(text, where, "<rgb>")
            if len(values) not in (1, 3):
                raise where.error(f"<rgb> takes one or three numbers, got {len(values)}")
            return tuple(values * 3 if len(values) == 1 else values)
        return text  # string

    def parse_spectrum(self, attrs: dict, where: Where, file: "_File") -> Spectrum:
        if ("value" in attrs) == ("filename" in attrs):
            raise where.error("<spectrum> needs a value or a filename attribute (not both)")
        if "filename" in attrs:
            path = file.resolve(attrs["filename"], self.main, self.folders)
            if path is None:
                raise where.error(f"<spectrum>: file '{attrs['filename']}' not found")
            try:
                wavelengths, values = read_spd(path)
            except (OSError, ValueError) as exc:
                raise where.error(f"<spectrum>: {path.name}: {exc}") from None
        else:
            tokens = [t for t in SPLIT.split(attrs["value"].strip()) if t]
            if len(tokens) == 1 and ":" not in tokens[0]:
                return Spectrum((), (number(tokens[0], where),))
            wavelengths, values = [], []
            for token in tokens:
                pair = token.split(":")
                if len(pair) != 2:
                    raise where.error(f"<spectrum>: '{token}' is not a wavelength:value pair")
                wavelengths.append(number(pair[0], where))
                values.append(number(pair[1], where))
        if len(wavelengths) < 2:
            raise where.error("<spectrum> needs one value, or at least two wavelength:value pairs")
        if any(b <= a for a, b in zip(wavelengths, wavelengths[1:])):
            raise where.error("<spectrum>: the wavelengths must increase")
        return Spectrum(tuple(wavelengths), tuple(values))

    def parse_transform(self, element: _Element, file: "_File") -> np.ndarray:
        matrix = np.eye(4)
        for op in element.children:
            where = self.where(op, file)
            if op.tag not in TRANSFORM_OPS:
                raise where.error(f"<{op.tag}> cannot be inside <transform> (translate, rotate, scale, matrix, "
                                  f"lookat can)")
            matrix = transform_op(op.tag, self.attrs(op, where), where) @ matrix
        return matrix


@dataclass
class _File:
    """The file being read: its path, the main file's line of its include (None for the main file), the chain
    of files that include it (resolved), whether it predates Mitsuba 2 (camelCase names), `<path>` folders."""

    path: Path
    top: Optional[int]
    chain: tuple
    old: bool

    def resolve(self, name: str, main: Path, folders: list) -> Optional[Path]:
        """A file name as Mitsuba's file resolver finds it: absolute, or relative to this file's folder, the main
        file's folder, or a `<path>` folder."""
        return find_file(name, [self.path.parent, main.parent] + folders)


def find_file(name: str, folders: list) -> Optional[Path]:
    """`name` if it is an absolute path to a file that exists, else the first folder/name that exists."""
    candidate = Path(name).expanduser()
    if candidate.is_absolute():
        return candidate if candidate.exists() else None
    for folder in folders:
        if (folder / candidate).exists():
            return folder / candidate
    return None


# ------------------------------------------------------------------------------------------------ helpers


def camel_to_snake(name: str) -> str:
    """Mitsuba's camel_to_underscore_case: `intIOR` → `int_ior`, `toWorld` → `to_world`."""
    return re.sub(r"(?<=[a-z])([A-Z]+)", lambda m: "_" + m.group(1).lower(), name)


def _upgrade_v1(node: Node) -> None:
    """What Mitsuba 3 changes in an object of a file older than 2.0.0, besides the names (see `add`)."""
    if node.type == "diffuse" and "diffuse_reflectance" in node.props:
        node.props["reflectance"] = node.props.pop("diffuse_reflectance")
    moved = {k: node.props.pop(k) for k in ("uoffset", "voffset", "uscale", "vscale") if k in node.props}
    if moved:
        get = {}
        for key, item in moved.items():
            if not (isinstance(item, Value) and item.kind in ("float", "integer")):
                raise item.where.error(f"{node.label()}: '{key}' must be a number")
            get[key] = float(item.value)
        to_uv = np.eye(4)  # scale(uscale, vscale) · translate(uoffset, voffset)
        to_uv[0, 0], to_uv[1, 1] = get.get("uscale", 1.0), get.get("vscale", 1.0)
        to_uv[:2, 3] = to_uv[0, 0] * get.get("uoffset", 0.0), to_uv[1, 1] * get.get("voffset", 0.0)
        node.props["to_uv"] = Value("transform", to_uv, node.where)


def _resolve_refs(root: Node, ids: dict[str, Node]) -> None:
    """Replace every Ref by the object it names (an error at the ref's line for an unknown id), then refuse a
    ref that leads back to an object containing it."""
    seen: set[int] = set()
    stack = [root]
    while stack:
        node = stack.pop()
        if id(node) in seen:
            continue
        seen.add(id(node))
        for i, (name, item) in enumerate(node.objects):
            if isinstance(item, Ref):
                if item.id not in ids:
                    known = ", ".join(sorted(ids)[:8]) or "none"
                    raise item.where.error(f"<ref id=\"{item.id}\">: no object has that id (ids: {known})")
                target = ids[item.id]
                node.objects[i] = (name, target)
                if name is not None:
                    node.props[name] = target
            stack.append(node.objects[i][1])
    _check_cycles(root, [], set())


def _check_cycles(node: Node, path: list, done: set) -> None:
    if id(node) in done:
        return
    if any(node is p for p in path):
        raise node.where.error(f"{node.label()} contains itself through <ref>s")
    path.append(node)
    for _, child in node.objects:
        _check_cycles(child, path, done)
    path.pop()
    done.add(id(node))
