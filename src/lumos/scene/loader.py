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
such lines (`messages.format_validation_error`, also used for settings given in Python or on the command line).

YAML is read with `yaml.SafeLoader` only: tags that would build Python objects are refused, duplicate keys
are errors, and floats may be written `1e-3` as in JSON and YAML 1.2.
"""

from __future__ import annotations

import os
import re
import types
from pathlib import Path
from typing import Any, Optional

import yaml
from pydantic import ValidationError

from ..errors import LumosError, SceneError
from ..io.models import MODEL_FORMATS
from .messages import format_path, format_validation_error, location, one_line, show
from .model import Mesh, ModelInclude, Scene

SCENE_SUFFIXES = (".yaml", ".yml", ".json")
#: Other renderers' scene files, read into lumos's scene format: suffix -> (module under lumos.io, function). The
#: function takes the file's Path and returns (data, lines): a scene dict as a YAML file would give it (mesh and
#: image paths relative to the file's folder) and {key path tuple: line in the file} for the messages (or None);
#: it raises LumosError `<file>:<line>: <what>` on bad input and warns (LumosWarning) once per stand-in.
FOREIGN_SCENES = {".xml": ("mitsuba", "read_mitsuba"), ".pbrt": ("pbrt", "read_pbrt")}
_TOP_KEYS = ", ".join(Scene.model_fields)


# ------------------------------------------------------------------------------------------------ entry point


def load_scene(source: str | os.PathLike | dict, view: Optional[str] = None, up: Optional[str] = None,
               folder: Optional[str | os.PathLike] = None) -> Scene:
    """Load, validate and complete a scene from a `.yaml`/`.yml`/`.json` file, a dict, or a model file (`.obj`,
    `.gltf`, `.glb`, `.ply`, `.stl`, `.off`: the model with a camera, lights and a method made up for it).

    Mesh files are read (relative to the scene file's folder, or for a dict to `folder`, by default the current
    folder: a scene file's dict edited in memory, as the preview page does, keeps its folder). For a model
    file, `view` (three-quarter, front, back, left, right or top) and `up` ("y" or "z") choose the made-up
    camera; for a scene, which has its own camera, they are refused.
    Raises `SceneError` (a `LumosError`) with a one-line message for any bad input.
    """
    is_model = isinstance(source, (str, os.PathLike)) and Path(source).suffix.lower() in MODEL_FORMATS
    if (view is not None or up is not None) and not is_model:
        raise SceneError(f"{os.fspath(source) if isinstance(source, (str, os.PathLike)) else 'scene'}: --view and "
                         f"--up frame a model file; a scene has its own camera")
    if isinstance(source, Scene):
        return _completed(source)
    if isinstance(source, (dict, list)):
        name, path, lines, data = "scene", None, None, source
    elif isinstance(source, (str, os.PathLike)):
        name, path = os.fspath(source), Path(source).expanduser()
        if path.suffix.lower() in MODEL_FORMATS:
            return _model_scene(path, name, view, up)
        if path.suffix.lower() in FOREIGN_SCENES:
            data, lines = _read_foreign(path, name)
        else:
            data, lines = _read_file(path, name)
    else:
        raise SceneError(f"load_scene() takes a file path or a dict, not {type(source).__name__}")
    if not isinstance(data, dict):
        raise SceneError(f"{location(name, lines, ())}: the top level must be a mapping ({_TOP_KEYS}), "
                         f"got {show(data)}")
    folder = path.parent if path else Path(folder) if folder is not None else Path.cwd()
    included = []
    data = _camera_from_file(data, folder, name, lines, included)
    try:
        scene = Scene.model_validate(data)
    except ValidationError as exc:
        raise SceneError(format_validation_error(exc, name, lines=lines, data=data)) from None
    if scene.animation is not None:
        _check_animation(scene, name, lines)
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


def _read_foreign(path: Path, name: str) -> tuple[Any, Optional[dict]]:
    """A Mitsuba 3 or pbrt-v4 scene file read into lumos's scene format (FOREIGN_SCENES)."""
    import importlib

    if path.is_dir():
        raise SceneError(f"{name}: is a folder, not a scene file")
    if not path.is_file():
        raise SceneError(f"{name}: no such file")
    module, function = FOREIGN_SCENES[path.suffix.lower()]
    read = getattr(importlib.import_module(f"..io.{module}", __package__), function)
    try:
        return read(path)
    except LumosError as exc:
        reason = one_line(str(exc))
        for long in (str(path.resolve()), str(path)):  # the file as the user named it
            reason = reason.replace(long, name)
        raise SceneError(reason) from None


def _read_file(path: Path, name: str) -> tuple[Any, dict]:
    if path.is_dir():
        raise SceneError(f"{name}: is a folder, not a scene file")
    if path.suffix.lower() not in SCENE_SUFFIXES:
        raise SceneError(f"{name}: scene files must end in .yaml, .yml or .json (or be Mitsuba 3 .xml or pbrt-v4 "
                         f".pbrt scenes), and model files in {', '.join(MODEL_FORMATS)}")
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
        raise SceneError(f"{name}: invalid YAML: {one_line(str(exc))}") from None
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
    return f"{where}: invalid YAML: {one_line(what)}"


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


def _check_animation(scene: Scene, name: str, lines: Optional[dict]) -> None:
    """The animation's tracks against the scene (targets, key order, key values): `animation.check`."""
    from .animation import AnimationError, check

    try:
        check(scene)
    except AnimationError as exc:
        raise SceneError(f"{location(name, lines, exc.where)}: {exc}") from None


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
                _load_mesh_file(obj, folder, location(name, lines, at + ("file",)))


def _resolve_texture_files(scene: Scene, folder: Path, name: str, lines: Optional[dict]) -> None:
    """Image textures, bump maps and the environment name files relative to the scene's folder; each must exist."""
    env = getattr(scene, "environment", None)  # (a stand-in namespace of an include has none)
    if env is not None and env.file is not None:
        path = (folder / Path(env.file).expanduser()).resolve()
        if not path.is_file():
            raise SceneError(f"{location(name, lines, ('environment', 'file'))}: no such image file {env.file!r}")
        env._path = path
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
                raise SceneError(f"{location(name, lines, at + key + ('file',))}: no such image file {tex.file!r}")
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
        raise SceneError(f"{where}: cannot read {mesh.file!r}: {type(exc).__name__}: {one_line(str(exc))}") from None
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
    return one_line(message[match.end():] if match else message)


# ------------------------------------------------------------------------------------ model files (includes)


def _import(path: Path, shown: str):
    """`import_model(path)` with its warnings said, each distinct one once (they name their file and line)."""
    import warnings

    from ..errors import LumosWarning
    from ..io.models import import_model

    try:
        model = import_model(path)
    except LumosError:
        raise
    except Exception as exc:  # a corrupt file can upset a parser in any way; it is still bad input
        raise LumosError(f"{shown}: {type(exc).__name__}: {one_line(str(exc))}") from None
    for text in model.warnings_once():  # each distinct problem once, with a count
        warnings.warn(LumosWarning(one_line(text)))
    return model


def _model_scene(path: Path, name: str, view: Optional[str] = None, up: Optional[str] = None) -> Scene:
    """The scene `lumos render model.obj` renders: the model with a camera, lights and a method made up for it
    (`lumos.scene.from_model`)."""
    from .from_model import VIEWS, scene_from_model

    if view is not None and view not in VIEWS:
        raise SceneError(f"--view: unknown view {view!r} (choose from {', '.join(VIEWS)})")
    if up is not None and up not in ("y", "z"):
        raise SceneError(f"--up: expected y or z, got {up!r}")

    if path.is_dir():
        raise SceneError(f"{name}: is a folder, not a model file")
    try:
        model = _import(path, name)
    except LumosError as exc:
        raise SceneError(one_line(str(exc))) from None
    data, about = scene_from_model(model, view, up)
    try:
        scene = Scene.model_validate(data)
    except ValidationError as exc:
        raise SceneError(format_validation_error(exc, name, data=data)) from None
    _resolve_texture_files(scene, path.parent, name, None)
    n = len(model.objects)
    scene._included = [f"{path.name}: {n} object{'s' if n != 1 else ''}, {len(model.materials)} materials; "
                       f"made up: {about}"]
    scene._source = path
    scene._made_for_model = True
    return scene


def _model_path(file: Any, folder: Path, where: str) -> Path:
    if not isinstance(file, str) or not file:
        raise SceneError(f"{where}: expected the path of a model file ({', '.join(MODEL_FORMATS)}), got {show(file)}")
    path = Path(file).expanduser()
    return path if path.is_absolute() else folder / path


def _read_model(file: str, folder: Path, where: str):
    path = _model_path(file, folder, where)
    try:
        return _import(path, file)
    except LumosError as exc:
        reason = one_line(str(exc))
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
        raise SceneError(f"{location(name, lines, ('camera', 'index'))}: expected a camera number >= 0, "
                         f"got {show(index)}")
    file = camera["file"]
    model = _read_model(file, folder, location(name, lines, ("camera", "file")))
    if index >= len(model.cameras):
        has = f"it has {len(model.cameras)} (0 to {len(model.cameras) - 1})" if model.cameras else "it has none"
        at = ("camera", "index") if "index" in camera else ("camera", "file")
        raise SceneError(f"{location(name, lines, at)}: {file!r} has no camera {index} ({has})")
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
        model = _read_model(obj.file, folder, location(name, lines, at + ("file",)))
        for key in obj.materials_override:
            if key not in model.materials:
                known = ", ".join(sorted(model.materials)) or "it has none"
                raise SceneError(f"{location(name, lines, at + ('materials_override', key))}: {obj.file!r} has no "
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
        where = f"{location(name, lines, at + ('file',))}: {obj.file}"
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
