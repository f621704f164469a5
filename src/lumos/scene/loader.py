"""Load a scene from a YAML/JSON file or a dict, validate it, and read the mesh files it names.

Every problem with the input ends in one `SceneError` whose message is a single line:

    <file>:<line>: <key path>: <what is wrong>

for example

    scene.yaml:12: objects[2].radius: must be greater than 0, got -1
    scene.yaml:7: objects[0]: unknown key 'radus' (did you mean 'radius'?)
    scene.yaml:3:9: invalid YAML: mapping values are not allowed here

The line is that of the offending key (or of the closest enclosing key that exists, for a missing one); it is
left out for dicts, whose "file" is `scene`. Key paths are written `objects[2].radius`, `lights[0].corner`,
`materials.red.kd`. Validation itself is pydantic's (`lumos.scene.model`); this module turns its errors into
such lines (`format_validation_error`, also used for settings given in Python or on the command line).

YAML is read with `yaml.SafeLoader` only: tags that would build Python objects are refused, duplicate keys
are errors, and floats may be written `1e-3` as in JSON and YAML 1.2.
"""

from __future__ import annotations

import difflib
import os
import re
import types
from pathlib import Path
from typing import Annotated, Any, Literal, Optional, Union, get_args, get_origin

import yaml
from pydantic import BaseModel, Tag, ValidationError

from ..errors import LumosError, SceneError
from ..io.models import MODEL_FORMATS
from . import model as _model
from .model import Mesh, ModelInclude, Scene, UnknownMaterial

SCENE_SUFFIXES = (".yaml", ".yml", ".json")
_TOP_KEYS = ", ".join(Scene.model_fields)


# ------------------------------------------------------------------------------------------------ entry point


def load_scene(source: str | os.PathLike | dict) -> Scene:
    """Load, validate and complete a scene from a `.yaml`/`.yml`/`.json` file or a dict.

    Mesh files are read (relative to the scene file's folder, or to the current folder for a dict).
    Raises `SceneError` (a `LumosError`) with a one-line message for any bad input.
    """
    if isinstance(source, Scene):
        return _completed(source)
    if isinstance(source, (dict, list)):
        name, path, lines, data = "scene", None, None, source
    elif isinstance(source, (str, os.PathLike)):
        name, path = os.fspath(source), Path(source).expanduser()
        if path.suffix.lower() in MODEL_FORMATS:
            return _model_scene(path, name)
        data, lines = _read_file(path, name)
    else:
        raise SceneError(f"load_scene() takes a file path or a dict, not {type(source).__name__}")
    if not isinstance(data, dict):
        raise SceneError(f"{_where(name, lines, ())}: the top level must be a mapping ({_TOP_KEYS}), "
                         f"got {_show(data)}")
    folder = path.parent if path else Path.cwd()
    included = []
    data = _camera_from_file(data, folder, name, lines, included)
    try:
        scene = Scene.model_validate(data)
    except ValidationError as exc:
        raise SceneError(format_validation_error(exc, name, lines=lines, data=data)) from None
    _load_meshes(scene, folder, name, lines)
    _resolve_texture_files(scene, folder, name, lines)
    _expand_models(scene, folder, name, lines, included)
    scene._included = included
    if path is not None:
        scene._source = path
    return scene


def _completed(scene: Scene) -> Scene:
    """A Scene built in Python (`Scene.model_validate`) gets what `load_scene` gives a file or a dict: mesh files
    read, image paths resolved, `type: model` includes expanded (paths relative to the scene's file, else to
    the current folder). A scene `load_scene` made is returned as it is."""
    folder = scene.source.parent if scene.source is not None else Path.cwd()
    for i, top in enumerate(scene.objects):
        for obj, at in _solids(top, ("objects", i)):
            if isinstance(obj, Mesh) and obj.file is not None and obj.vertices is None:
                _load_mesh_file(obj, folder, f"scene: {format_path(at + ('file',))}")
    _resolve_texture_files(scene, folder, "scene", None)
    included = list(scene._included or [])
    _expand_models(scene, folder, "scene", None, included)
    scene._included = included
    return scene


# ------------------------------------------------------------------------------------------- reading YAML


class _Loader(yaml.SafeLoader):
    """SafeLoader that also reads `1e-3` and `2E5` as floats (YAML 1.1 wants a dot)."""


_Loader.add_implicit_resolver(
    "tag:yaml.org,2002:float",
    re.compile(r"^[-+]?(?:[0-9][0-9_]*)(?:\.[0-9_]*)?[eE][-+]?[0-9]+$"),
    list("-+0123456789"),
)

_YAML = "tag:yaml.org,2002:"
_PLAIN_SCALARS = {_YAML + t for t in ("str", "int", "float", "bool", "null")}


def _read_file(path: Path, name: str) -> tuple[Any, dict]:
    if path.is_dir():
        raise SceneError(f"{name}: is a folder, not a scene file")
    if path.suffix.lower() not in SCENE_SUFFIXES:
        raise SceneError(f"{name}: scene files must end in .yaml, .yml or .json, and model files in "
                         f"{', '.join(MODEL_FORMATS)}")
    try:
        raw = path.read_bytes()
    except FileNotFoundError:
        raise SceneError(f"{name}: no such file") from None
    except OSError as exc:
        raise SceneError(f"{name}: cannot read: {exc.strerror or exc}") from None
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise SceneError(f"{name}: not a UTF-8 text file (byte 0x{raw[exc.start]:02x} at offset {exc.start})") from None
    if path.suffix.lower() == ".json":
        text = text.replace("\t", " ")  # JSON allows tabs as whitespace (never raw inside strings); YAML does not
    return parse_yaml(text, name)


def parse_yaml(text: str, name: str) -> tuple[Any, dict]:
    """Parse YAML text into plain data and a map key path -> line number (1-based)."""
    try:
        loader = _Loader(text)
    except yaml.reader.ReaderError as exc:  # control characters and the like, found before parsing starts
        line = text.count("\n", 0, exc.position) + 1
        raise SceneError(f"{name}:{line}: invalid YAML: {exc.reason} (character #x{exc.character:04x})") from None
    try:
        node = loader.get_single_node()
        if node is None:
            raise SceneError(f"{name}: the file is empty (a scene is a mapping with keys such as {_TOP_KEYS})")
        builder = _Builder(loader, name)
        return builder.build(node, ()), builder.lines
    except yaml.MarkedYAMLError as exc:
        raise SceneError(_yaml_error(exc, name)) from None
    except yaml.YAMLError as exc:
        raise SceneError(f"{name}: invalid YAML: {_one_line(str(exc))}") from None
    except RecursionError:
        raise SceneError(f"{name}: invalid YAML: nested too deeply") from None
    finally:
        loader.dispose()


def _yaml_error(exc: yaml.MarkedYAMLError, name: str) -> str:
    mark = exc.problem_mark or exc.context_mark
    where = f"{name}:{mark.line + 1}:{mark.column + 1}" if mark else name
    what = exc.problem or exc.context or "syntax error"
    if exc.context and exc.problem and exc.context.startswith("while") and exc.context_mark:
        what += f" ({exc.context} started on line {exc.context_mark.line + 1})"
    elif exc.context and exc.problem:
        what = f"{exc.context}, {exc.problem}"  # "expected a single document in the stream, but found another"
    return f"{where}: invalid YAML: {_one_line(what)}"


class _Builder:
    """Builds plain dicts/lists/scalars from a composed node tree, recording the line of every key and item."""

    def __init__(self, loader: yaml.SafeLoader, name: str):
        self.loader, self.name = loader, name
        self.lines: dict[tuple, int] = {}
        self._done: dict[int, Any] = {}  # aliases share one value (and cannot blow up exponentially)
        self._active: set[int] = set()

    def build(self, node: yaml.Node, path: tuple) -> Any:
        self.lines.setdefault(path, node.start_mark.line + 1)
        if id(node) in self._done:
            return self._done[id(node)]
        if id(node) in self._active:
            self.fail(node, path, "an alias refers to itself (recursive structure)")
        self._active.add(id(node))
        if isinstance(node, yaml.MappingNode):
            self.check_tag(node, path, {_YAML + "map"})
            value = self.mapping(node, path)
        elif isinstance(node, yaml.SequenceNode):
            self.check_tag(node, path, {_YAML + "seq"})
            value = [self.build(item, path + (i,)) for i, item in enumerate(node.value)]
        else:
            value = self.scalar(node, path)
        self._active.discard(id(node))
        self._done[id(node)] = value
        return value

    def mapping(self, node: yaml.MappingNode, path: tuple) -> dict:
        result: dict = {}
        first: dict[Any, int] = {}
        merges = []
        for key_node, value_node in node.value:
            if key_node.tag == _YAML + "merge":
                merges.append((key_node, value_node))
                continue
            if not isinstance(key_node, yaml.ScalarNode):
                self.fail(key_node, path, "a key must be a plain name, not a list or mapping")
            key = self.scalar(key_node, path)
            line = key_node.start_mark.line + 1
            if key in first:
                self.fail(key_node, path + (key,), f"duplicate key '{key}' (first given on line {first[key]})")
            first[key] = line
            self.lines[path + (key,)] = line
            result[key] = self.build(value_node, path + (key,))
        for key_node, value_node in merges:  # `<<: *base` — explicit keys win, earlier sources first
            sources = value_node.value if isinstance(value_node, yaml.SequenceNode) else [value_node]
            for source in sources:
                if not isinstance(source, yaml.MappingNode):
                    self.fail(key_node, path, "'<<' must merge a mapping or a list of mappings")
                for key, value in self.build(source, path).items():
                    self.lines.setdefault(path + (key,), key_node.start_mark.line + 1)
                    result.setdefault(key, value)
        return result

    def scalar(self, node: yaml.ScalarNode, path: tuple) -> Any:
        if node.tag == _YAML + "timestamp":
            return node.value  # a date-like string stays a string
        self.check_tag(node, path, _PLAIN_SCALARS)
        try:
            return self.loader.construct_object(node, deep=True)
        except (yaml.YAMLError, ValueError):
            self.fail(node, path, f"cannot read {node.value!r} as {_short_tag(node.tag)}")

    def check_tag(self, node: yaml.Node, path: tuple, allowed: set) -> None:
        if node.tag not in allowed:
            self.fail(node, path, f"YAML tag '{_short_tag(node.tag)}' is not allowed (scene files hold plain "
                                  f"data only: mappings, lists, numbers, strings, true/false)")

    def fail(self, node: yaml.Node, path: tuple, message: str):
        where = f"{self.name}:{node.start_mark.line + 1}"
        raise SceneError(f"{where}: {format_path(path)}: {message}" if path else f"{where}: {message}")


def _short_tag(tag: str) -> str:
    return "!!" + tag[len(_YAML):] if tag.startswith(_YAML) else tag


# --------------------------------------------------------------------------------------------- mesh files


def _solids(obj, path: tuple):
    """(object, key path) of obj and, for a csg node, of every solid under it."""
    yield obj, path
    if getattr(obj, "type", None) == "csg":
        yield from _solids(obj.left, path + ("left",))
        yield from _solids(obj.right, path + ("right",))


def _load_meshes(scene: Scene, folder: Path, name: str, lines: Optional[dict]) -> None:
    for i, top in enumerate(scene.objects):
        for obj, at in _solids(top, ("objects", i)):
            if isinstance(obj, Mesh) and obj.file is not None:
                _load_mesh_file(obj, folder, _where(name, lines, at + ("file",)))


def _resolve_texture_files(scene: Scene, folder: Path, name: str, lines: Optional[dict]) -> None:
    """Image textures and bump maps name files relative to the scene's folder; each must exist."""
    materials = [(("materials", key), m) for key, m in scene.materials.items()]
    for i, top in enumerate(scene.objects):
        for obj, at in _solids(top, ("objects", i)):
            if obj.material is not None and not isinstance(obj.material, str):
                materials.append((at + ("material",), obj.material))
    for at, material in materials:
        maps = [(("texture", k) if isinstance(material.texture, list) else ("texture",), tex)
                for k, tex in enumerate(material.textures)]
        maps += [(("bump",), material.bump)] if material.bump is not None else []
        for key, tex in maps:
            if tex.file is None:
                continue
            path = (folder / Path(tex.file).expanduser()).resolve()
            if not path.is_file():
                raise SceneError(f"{_where(name, lines, at + key + ('file',))}: no such image file {tex.file!r}")
            tex._path = path


def _load_mesh_file(mesh: Mesh, folder: Path, where: str) -> None:
    from ..io.meshes import load_mesh  # trimesh and friends: only when a scene has mesh files

    path = Path(mesh.file).expanduser()
    path = path if path.is_absolute() else folder / path
    try:
        data = load_mesh(path)
    except LumosError as exc:
        raise SceneError(f"{where}: cannot read {mesh.file!r}: {_mesh_reason(str(exc), path)}") from None
    except Exception as exc:  # a corrupt file can upset a parser in any way; it is still bad input
        raise SceneError(f"{where}: cannot read {mesh.file!r}: {type(exc).__name__}: {_one_line(str(exc))}") from None
    mesh.vertices, mesh.faces, mesh.normals, mesh.uvs = data
    mesh._source = path
    try:
        mesh.check_arrays()
    except ValueError as exc:
        raise SceneError(f"{where}: bad mesh in {mesh.file!r}: {exc}") from None


def _mesh_reason(message: str, path: Path) -> str:
    """`cannot read mesh '<path>': <reason>` -> `<reason>`."""
    exact = f"cannot read mesh '{path}': "
    if message.startswith(exact):
        return message[len(exact):]
    match = re.match(r"cannot read mesh '.*?': ", message)
    return _one_line(message[match.end():] if match else message)


# ------------------------------------------------------------------------------------ model files (includes)


def _import(path: Path, shown: str):
    """`import_model(path)` with its warnings said, each prefixed by nothing (they name their file and line)."""
    import warnings

    from ..errors import LumosWarning
    from ..io.models import import_model

    try:
        model = import_model(path)
    except LumosError:
        raise
    except Exception as exc:  # a corrupt file can upset a parser in any way; it is still bad input
        raise LumosError(f"{shown}: {type(exc).__name__}: {_one_line(str(exc))}") from None
    for text in model.warnings:
        warnings.warn(LumosWarning(_one_line(text)))
    return model


def _model_scene(path: Path, name: str) -> Scene:
    """The scene `lumos render model.obj` renders: the model with a camera, lights and a method made up for it
    (`lumos.scene.from_model`)."""
    from .from_model import scene_from_model

    if path.is_dir():
        raise SceneError(f"{name}: is a folder, not a model file")
    try:
        model = _import(path, name)
    except LumosError as exc:
        raise SceneError(_one_line(str(exc))) from None
    data, about = scene_from_model(model)
    try:
        scene = Scene.model_validate(data)
    except ValidationError as exc:
        raise SceneError(format_validation_error(exc, name, data=data)) from None
    _resolve_texture_files(scene, path.parent, name, None)
    n = len(model.objects)
    scene._included = [f"{path.name}: {n} object{'s' if n != 1 else ''}, {len(model.materials)} materials; "
                       f"made up: {about}"]
    scene._source = path
    return scene


def _model_path(file: Any, folder: Path, where: str) -> Path:
    if not isinstance(file, str) or not file:
        raise SceneError(f"{where}: expected the path of a model file ({', '.join(MODEL_FORMATS)}), got {_show(file)}")
    path = Path(file).expanduser()
    return path if path.is_absolute() else folder / path


def _read_model(file: str, folder: Path, where: str):
    path = _model_path(file, folder, where)
    try:
        return _import(path, file)
    except LumosError as exc:
        reason = _one_line(str(exc))
        for long in (str(path), str(path.resolve())):  # `<file>:<line>: ...` from the importer: the name as given
            reason = reason.replace(long, file)
        raise SceneError(f"{where}: {reason}") from None


def _camera_from_file(data: dict, folder: Path, name: str, lines: Optional[dict], included: list) -> dict:
    """`camera: {file: model.gltf, index: 0, ...}`: the file's camera `index`, with the other keys given
    replacing its own. Returns `data` (a shallow copy when the camera was replaced)."""
    camera = data.get("camera")
    if not isinstance(camera, dict) or "file" not in camera:
        return data
    index = camera.get("index", 0)
    if not isinstance(index, int) or isinstance(index, bool) or index < 0:
        raise SceneError(f"{_where(name, lines, ('camera', 'index'))}: expected a camera number >= 0, "
                         f"got {_show(index)}")
    file = camera["file"]
    model = _read_model(file, folder, _where(name, lines, ("camera", "file")))
    if index >= len(model.cameras):
        has = f"it has {len(model.cameras)} (0 to {len(model.cameras) - 1})" if model.cameras else "it has none"
        at = ("camera", "index") if "index" in camera else ("camera", "file")
        raise SceneError(f"{_where(name, lines, at)}: {file!r} has no camera {index} ({has})")
    given = {k: v for k, v in camera.items() if k not in ("file", "index")}
    included.append(f"camera: camera {index} of {file}" + (f", with {', '.join(given)} given" if given else ""))
    return {**data, "camera": {**model.cameras[index], **given}}


def _expand_models(scene: Scene, folder: Path, name: str, lines: Optional[dict], included: list) -> None:
    """Replace every `type: model` object by the file's objects, and add its materials (and lights)."""
    from .from_model import include_pieces, transform_light

    if not any(isinstance(obj, ModelInclude) for obj in scene.objects):
        return
    objects, prefixes = [], set()
    for i, obj in enumerate(scene.objects):
        if not isinstance(obj, ModelInclude):
            objects.append(obj)
            continue
        at = ("objects", i)
        model = _read_model(obj.file, folder, _where(name, lines, at + ("file",)))
        for key in obj.materials_override:
            if key not in model.materials:
                known = ", ".join(sorted(model.materials)) or "it has none"
                raise SceneError(f"{_where(name, lines, at + ('materials_override', key))}: {obj.file!r} has no "
                                 f"material {key!r} (its materials: {known})")
        prefix = base = obj.name or Path(obj.file).name
        n = 1
        while prefix in prefixes or any(m.startswith(prefix + ":") for m in scene.materials):
            n += 1
            prefix = f"{base}#{n}"
        prefixes.add(prefix)
        matrix = obj.transform.to_matrix() if obj.transform is not None else None
        overrides = {k: m.model_dump(include=m.model_fields_set) for k, m in obj.materials_override.items()}
        materials, pieces = include_pieces(model, prefix, matrix, overrides, keep_materials=obj.material is None)
        lights = [transform_light(light, matrix) if matrix is not None else light for light in model.lights]
        part = {"materials": materials, "objects": pieces, "lights": lights if obj.lights else []}
        where = f"{_where(name, lines, at + ('file',))}: {obj.file}"
        try:
            sub = Scene.model_validate(part)
        except ValidationError as exc:
            raise SceneError(format_validation_error(exc, where, data=part)) from None
        _load_meshes(sub, folder, where, None)
        _resolve_texture_files(types.SimpleNamespace(materials=sub.materials, objects=[]), folder, where, None)
        if obj.material is not None:
            for piece in sub.objects:
                piece.material = obj.material
        scene.materials.update(sub.materials)
        scene.lights.extend(sub.lights)
        objects.extend(sub.objects)
        what = f"{len(sub.objects)} object{'s' if len(sub.objects) != 1 else ''}"
        what += f", {len(sub.materials)} materials as '{prefix}:...'" if obj.material is None else ", its material"
        what += f", {len(sub.lights)} lights" if obj.lights else ""
        if obj.materials_override:
            what += f" ({', '.join(obj.materials_override)} overridden)"
        included.append(f"{format_path(at)}: {obj.file}: {what}")
    scene.objects[:] = objects


# ------------------------------------------------------------------------------- pydantic errors -> one line


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
    text = f"{_where(source, lines, line_path, prefix + path)}: {message}"
    others = {same for _, _, _, same in explained[1:]} - {first}  # a vector 2 short is one error, not 2
    if others:
        text += f" (and {len(others)} more error{'s' if len(others) > 1 else ''})"
    return text


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


def _where(source: str, lines: Optional[dict], line_path: tuple, shown_path: Optional[tuple] = None) -> str:
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
    if kind == "value_error" and isinstance(ctx.get("error"), UnknownMaterial):
        where = ("objects", ctx["error"].index, "material")
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
        return f"expected {expected}, got {_show(value)}"
    if kind == "finite_number":
        return "is NaN or infinite"
    if kind in _BOUNDS:
        key, words = _BOUNDS[kind]
        return f"{words} {_num(ctx.get(key))}, got {_show(value, typed=False)}"
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
    shown = _show(value, typed=not isinstance(value, str))
    match = difflib.get_close_matches(value, choices, n=1, cutoff=0.6) if isinstance(value, str) else []
    if match:
        return f"unknown {what} {shown} (did you mean '{match[0]}'? {listed})"
    return f"unknown {what} {shown} ({listed})"


def _light_type_message(value: Any, tags: list[str]) -> str:
    kinds = list(dict.fromkeys(t.split(".")[0] for t in tags))
    shapes = [t.split(".", 1)[1] for t in tags if "." in t]
    if not isinstance(value, dict):
        return f"expected a mapping, got {_show(value)}"
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


def _show(value: Any, typed: bool = True) -> str:
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
        text = _one_line(repr(value))[:40]
    return f"{text} ({type(value).__name__})" if typed else text


def _one_line(text: str) -> str:
    return " ".join(text.split())
