"""glTF materials (pbrMetallicRoughness and the KHR material extensions) → lumos material dicts.

    materials = Materials(doc)        # doc: a gltf_document.Document
    name = materials.key(0)           # the lumos material name of glTF material 0 (converted once)
    materials.used                    # {name: material dict} of the materials the meshes use

The mapping (docs/formats.md#gltf-20 has the table): each glTF material becomes a lumos `principled` material
(`scene.materials.Principled`: glTF's own metallic–roughness BRDF, which `path` reads exactly) with its factors
(baseColorFactor, metallicFactor, roughnessFactor, KHR_materials_ior, _specular, _transmission, _clearcoat), and
textures:

    baseColorTexture          apply_to [base_color, and the classic ka, kd, ks, kr it tints], multiply
    metallicRoughnessTexture  apply_to [metallic_roughness] (raw: blue × metallic, green × roughness)
    occlusionTexture          apply_to [occlusion] (raw red × ka: the local methods' ambient)
    emissiveTexture           apply_to [emission], multiply, emission = emissiveFactor·emissiveStrength
    normalTexture             bump: {type: normal, strength: scale}

The local methods read its classic reading (`Principled.classic`: a Phong stand-in, kd + ks + kr + kt <= 1),
which takes the factors alone (not the metallic–roughness map). alphaMode BLEND with α < 1 makes the material
that classic reading with a see-through share, in every method.

Images: a texture's file is the image file itself (an absolute path) when the glTF names one; an embedded image
(a data URI, or a bufferView of a .glb) is written once, as its own PNG/JPEG bytes, to a cache folder made for
the process (`tempfile.mkdtemp`, removed at exit), named by the bytes' SHA-256, since a lumos texture names a
file. A missing or unreadable image is a warning and the material goes without that texture.
"""

from __future__ import annotations

import atexit
import hashlib
import io
import shutil
import tempfile
from pathlib import Path

import numpy as np

from ..scene.materials import Principled

#: sampler wrap modes
_REPEAT, _CLAMP, _MIRROR = 10497, 33071, 33648
#: largest shininess (a perfectly smooth surface)
_MAX_SHININESS = 1e4
_cache_dir: Path | None = None


class Materials:
    """The glTF document's materials, converted when a primitive first uses one."""

    def __init__(self, doc):
        self.doc = doc
        self.used: dict[str, dict] = {}
        #: the names of emissive materials that are not `doubleSided`: their objects emit on the front only
        self.one_sided_emitters: set[str] = set()
        self._names: dict[int, str] = {}
        self._images: dict[int, tuple[str, bool] | None] = {}

    def key(self, index: int) -> str:
        """The lumos material name of materials[index] (its glTF name, made unique), converting it once."""
        if index not in self._names:
            item = self.doc.item("materials", index, "material")
            name = item.get("name") if isinstance(item.get("name"), str) and item.get("name") else f"material{index}"
            if name in self.used:
                name = f"{name}#{index}"
            self._names[index] = name
            self.used[name] = self._convert(item, f"materials[{index}]")
            if "emission" in self.used[name] and item.get("doubleSided") is not True:
                self.one_sided_emitters.add(name)
        return self._names[index]

    # ---- the mapping

    def _convert(self, item: dict, at: str) -> dict:
        doc = self.doc
        pbr = doc.obj(item, "pbrMetallicRoughness", at)
        at_pbr = f"{at}.pbrMetallicRoughness"
        base = np.clip(doc.numbers(pbr, "baseColorFactor", at_pbr, [1.0, 1.0, 1.0, 1.0], 4), 0.0, 1.0)
        rgb, alpha = base[:3], float(base[3])
        ext = doc.obj(item, "extensions", at)
        at_ext = f"{at}.extensions"
        ior = doc.number(doc.obj(ext, "KHR_materials_ior", at_ext), "ior", f"{at_ext}.KHR_materials_ior", 1.5, 0.0,
                         1e3)
        ior = 1.5 if ior == 0.0 else max(ior, 1.0)  # 0 and values below 1 are not physical dielectrics
        spec = doc.obj(ext, "KHR_materials_specular", at_ext)
        at_spec = f"{at_ext}.KHR_materials_specular"
        model = {
            "base_color": rgb.tolist(),
            "metallic": doc.number(pbr, "metallicFactor", at_pbr, 1.0, 0.0, 1.0),
            "roughness": doc.number(pbr, "roughnessFactor", at_pbr, 1.0, 0.0, 1.0),
            "ior": ior,
            "specular": doc.number(spec, "specularFactor", at_spec, 1.0, 0.0, 1.0),
            "specular_color": np.clip(doc.numbers(spec, "specularColorFactor", at_spec, [1.0, 1.0, 1.0], 3), 0.0,
                                      None).tolist(),
            "transmission": doc.number(doc.obj(ext, "KHR_materials_transmission", at_ext), "transmissionFactor",
                                       f"{at_ext}.KHR_materials_transmission", 0.0, 0.0, 1.0),
        }
        coat = doc.obj(ext, "KHR_materials_clearcoat", at_ext)
        at_coat = f"{at_ext}.KHR_materials_clearcoat"
        model["clearcoat"] = doc.number(coat, "clearcoatFactor", at_coat, 0.0, 0.0, 1.0)
        model["clearcoat_roughness"] = doc.number(coat, "clearcoatRoughnessFactor", at_coat, 0.0, 0.0, 1.0)
        for key in ("clearcoatTexture", "clearcoatRoughnessTexture", "clearcoatNormalTexture"):
            if key in coat:
                doc.warn(f"{at_coat}.{key}: not read (lumos's clear coat takes the factors and the base's normal)")
        for key in ("specularTexture", "specularColorTexture"):
            if key in spec:
                doc.warn(f"{at_spec}.{key}: not read (lumos's principled material takes the specular factors)")
        if "transmissionTexture" in doc.obj(ext, "KHR_materials_transmission", at_ext):
            doc.warn(f"{at_ext}.KHR_materials_transmission.transmissionTexture: not read (the factor is)")
        mat = {"principled": model}
        strength = doc.number(doc.obj(ext, "KHR_materials_emissive_strength", at_ext), "emissiveStrength",
                              f"{at_ext}.KHR_materials_emissive_strength", 1.0, 0.0)
        emission = np.clip(doc.numbers(item, "emissiveFactor", at, [0.0, 0.0, 0.0], 3), 0.0, None) * strength
        if emission.any():
            mat["emission"] = emission
        classic = Principled(**model).classic()  # what the local methods read: its textures tint these
        textures = []
        base_tex = self._texture(pbr, "baseColorTexture", at_pbr) if "baseColorTexture" in pbr else None
        if base_tex is not None:
            targets = [k for k in ("ka", "kd", "ks", "kr") if np.any(np.asarray(classic[k]) > 0)]
            textures.append(dict(base_tex[0], apply_to=["base_color", *targets], mode="multiply"))
        if "metallicRoughnessTexture" in pbr:
            mr = self._texture(pbr, "metallicRoughnessTexture", at_pbr)
            if mr is not None:
                textures.append(dict(mr[0], apply_to=["metallic_roughness"]))
        if "emissiveTexture" in item and emission.any():
            emissive = self._texture(item, "emissiveTexture", at)
            if emissive is not None:
                textures.append(dict(emissive[0], apply_to=["emission"], mode="multiply"))
        if "occlusionTexture" in item:
            occlusion = self._texture(item, "occlusionTexture", at)
            if occlusion is not None:
                if doc.number(doc.obj(item, "occlusionTexture", at), "strength", f"{at}.occlusionTexture", 1.0) != 1:
                    doc.warn(f"{at}.occlusionTexture.strength: read as 1")
                textures.append(dict(occlusion[0], apply_to=["occlusion"]))
        self._alpha(item, at, mat, classic, alpha, base_tex, textures)
        if textures:
            mat["texture"] = textures[0] if len(textures) == 1 else textures
        if "normalTexture" in item:
            normal = self._texture(item, "normalTexture", at)
            if normal is not None:
                info = doc.obj(item, "normalTexture", at)
                scale = doc.number(info, "scale", f"{at}.normalTexture", 1.0)
                bump = {k: v for k, v in normal[0].items() if k != "apply_to"}
                mat["bump"] = dict(bump, type="normal", strength=scale)
        return {k: (v.tolist() if isinstance(v, np.ndarray) else v) for k, v in mat.items()}

    def _alpha(self, item: dict, at: str, mat: dict, classic: dict, alpha: float, base_tex, textures: list) -> None:
        """alphaMode MASK: the base texture's alpha as an opacity cut-out (lumos cuts at 0.5); BLEND: the same
        cut-out, and the factor's alpha as a see-through share kt = 1 − α (ior 1) with the rest scaled by α: the
        classic reading (`classic`) of the material, which then stands for it in every method (`path` too)."""
        mode = item.get("alphaMode", "OPAQUE")
        if mode not in ("OPAQUE", "MASK", "BLEND"):
            raise self.doc.error(f"{at}.alphaMode", f"must be OPAQUE, MASK or BLEND, got {mode!r}")
        if mode == "OPAQUE":
            return
        cutoff = self.doc.number(item, "alphaCutoff", at, 0.5, 0.0, 1.0)
        if mode == "MASK" and cutoff != 0.5:
            self.doc.warn(f"{at}.alphaCutoff: {cutoff} read as 0.5 (lumos's opacity cut-out)")
        if base_tex is not None and base_tex[1]:  # the image has an alpha channel
            textures.append(dict(base_tex[0], apply_to=["opacity"]))
        coverage = alpha if mode == "BLEND" else float(alpha >= cutoff)
        if coverage < 1.0:  # a see-through share: the classic model's kt (no principled model draws it)
            del mat["principled"]
            for k in ("ka", "kd", "ks", "kr", "kt", "shininess", "ior"):
                mat[k] = classic.get(k, 0.0 if k != "ior" else 1.0)
            for k in ("ka", "kd", "ks", "kr", "kt", "emission"):
                if k in mat:
                    mat[k] = np.asarray(mat[k]) * coverage
            mat["kt"] = np.asarray(mat["kt"]) + (1.0 - coverage)
            if classic.get("fresnel"):
                mat["fresnel"] = True
            for tex in textures:
                tex["apply_to"] = [k for k in tex["apply_to"] if k not in ("base_color", "metallic_roughness")]
            textures[:] = [tex for tex in textures if tex["apply_to"]]

    # ---- textures and images

    def _texture(self, holder: dict, key: str, at: str) -> tuple[dict, bool] | None:
        """(lumos image texture dict, whether the image has alpha) of a textureInfo, or None (warned) when its
        image cannot be used."""
        doc = self.doc
        info = doc.obj(holder, key, at)
        at = f"{at}.{key}"
        index = doc.index(info, "index", at, "textures")
        tex = doc.item("textures", index, f"{at}.index")
        at_tex = f"textures[{index}]"
        if "source" not in tex:
            doc.warn(f"{at_tex}: no source image (an extension's image format?): texture skipped")
            return None
        image = self._image(doc.index(tex, "source", at_tex, "images"))
        if image is None:
            return None
        out = {"type": "image", "file": image[0], "wrap": self._wrap(tex, at_tex)}
        transform = doc.obj(doc.obj(info, "extensions", at), "KHR_texture_transform", f"{at}.extensions")
        coord = transform.get("texCoord", info.get("texCoord", 0))
        if coord != 0 and not self._same_as_first_uvs(coord):
            doc.warn(f"{at}: texCoord {coord}: lumos reads TEXCOORD_0 only")
        if transform:
            at_t = f"{at}.extensions.KHR_texture_transform"
            su, sv = doc.numbers(transform, "scale", at_t, [1.0, 1.0], 2)
            ou, ov = doc.numbers(transform, "offset", at_t, [0.0, 0.0], 2)
            if doc.number(transform, "rotation", at_t, 0.0) != 0.0:
                doc.warn(f"{at_t}.rotation: not read (lumos textures take a scale and an offset)")
            if su <= 0 or sv <= 0:
                doc.warn(f"{at_t}.scale: {[su, sv]} read as its size (lumos scales are positive)")
                su, sv = abs(su) or 1.0, abs(sv) or 1.0
            # glTF looks up (su·u + ou, sv·v + ov) with v down; lumos (su·u + o_u, sv·(1 − v) + o_v) with v up,
            # so the same texel needs o_v = 1 − sv − ov
            out["scale"] = [su, sv]
            offset = [ou, 1.0 - sv - ov]
            if offset != [0.0, 0.0]:
                out["offset"] = offset
        return out, image[1]

    def _same_as_first_uvs(self, coord) -> bool:
        """Whether every primitive that has TEXCOORD_<coord> has TEXCOORD_0's accessor there (exporters often
        point both sets at one accessor), so that reading TEXCOORD_0 reads the set the texture names."""
        attributes = [prim.get("attributes", {}) for mesh in self.doc.json.get("meshes", []) if isinstance(mesh, dict)
                      for prim in mesh.get("primitives", []) if isinstance(prim, dict)]
        named = [a for a in attributes if isinstance(a, dict) and f"TEXCOORD_{coord}" in a]
        return bool(named) and all(a[f"TEXCOORD_{coord}"] == a.get("TEXCOORD_0") for a in named)

    def _wrap(self, tex: dict, at: str) -> str:
        if "sampler" not in tex:
            return "repeat"
        doc = self.doc
        s = doc.index(tex, "sampler", at, "samplers")
        sampler = doc.item("samplers", s, f"{at}.sampler")
        modes = {doc.int(sampler, k, f"samplers[{s}]", default=_REPEAT) for k in ("wrapS", "wrapT")}
        if _MIRROR in modes:
            doc.warn(f"samplers[{s}]: mirrored repeat read as repeat")
        if modes == {_CLAMP}:
            return "clamp"
        if _CLAMP in modes:
            doc.warn(f"samplers[{s}]: clamp on one axis and repeat on the other read as repeat on both")
        return "repeat"

    def _image(self, index: int) -> tuple[str, bool] | None:
        """(absolute path of the image file, has alpha) of images[index], or None (warned)."""
        if index in self._images:
            return self._images[index]
        doc = self.doc
        item = doc.item("images", index, "source")
        at = f"images[{index}]"
        result = None
        try:
            if "uri" in item and isinstance(item["uri"], str) and not item["uri"].startswith("data:"):
                path = doc.uri_path(item["uri"])
                data = path.read_bytes() if path.is_file() else None
                if data is None:
                    doc.warn(f"{at}.uri: no such image file {str(path)!r}: texture skipped")
            elif "uri" in item:
                data, path = doc.uri_bytes(item, at), None
            else:
                view = doc.index(item, "bufferView", at, "bufferViews")
                buf, offset, length, _ = doc.buffer_view(view, f"{at}.bufferView")
                data, path = buf[offset : offset + length], None
            if data is not None:
                result = self._checked(data, path, at)
        except Exception as exc:  # noqa: BLE001 -- an unusable image is a warning, whatever went wrong
            from ..errors import LumosError

            if not isinstance(exc, LumosError):
                raise
            doc.warn(f"{at}: {str(exc).split(': ', 1)[-1]}: texture skipped")
        self._images[index] = result
        return result

    def _checked(self, data: bytes, path: Path | None, at: str) -> tuple[str, bool] | None:
        from PIL import Image as PILImage

        kind = ".png" if data[:8] == b"\x89PNG\r\n\x1a\n" else ".jpg" if data[:3] == b"\xff\xd8\xff" else None
        if kind is None:
            self.doc.warn(f"{at}: not a PNG or JPEG image: texture skipped")
            return None
        try:
            with PILImage.open(io.BytesIO(data)) as img:
                img.load()
                alpha = img.mode in ("RGBA", "LA", "PA", "La", "RGBa") or "transparency" in img.info
        except Exception as exc:  # noqa: BLE001 -- Pillow raises many kinds on corrupt images
            self.doc.warn(f"{at}: unreadable image ({type(exc).__name__}): texture skipped")
            return None
        if path is None:
            path = cache_folder() / (hashlib.sha256(data).hexdigest()[:24] + kind)
            if not path.is_file():
                path.write_bytes(data)
        return str(path), alpha


def shininess(rough: float) -> float:
    """The Phong exponent of glTF roughness r: Beckmann α = r², Blinn-Phong n_B = 2/α² − 2, Phong n = n_B/4,
    clamped to [1, 10⁴]."""
    if rough < 0.05:  # 0.5·(1/0.05⁴ − 1) > 10⁴ already
        return _MAX_SHININESS
    return float(min(max(0.5 * (rough ** -4 - 1.0), 1.0), _MAX_SHININESS))


def cache_folder() -> Path:
    """The folder embedded images are written to: made once per process, removed when it exits."""
    global _cache_dir
    if _cache_dir is None or not _cache_dir.is_dir():
        _cache_dir = Path(tempfile.mkdtemp(prefix="lumos-gltf-"))
        atexit.register(shutil.rmtree, _cache_dir, True)
    return _cache_dir

