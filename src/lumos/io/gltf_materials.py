"""glTF materials (pbrMetallicRoughness and the KHR material extensions) → lumos's classic material dicts.

    materials = Materials(doc)        # doc: a gltf_document.Document
    name = materials.key(0)           # the lumos material name of glTF material 0 (converted once)
    materials.used                    # {name: material dict} of the materials the meshes use

The mapping (docs/formats.md#gltf-20 has the table and the reasons), with base colour b, metallic m,
roughness r, the dielectric's normal-incidence reflectance F0 = ((ior − 1)/(ior + 1))² (0.04 at ior 1.5),
transmission t and g = (1 − r)² the share of the specular reflection that is a sharp mirror:

    kd      = b·(1 − m)·(1 − F0)·(1 − t)     the dielectric's diffuse part (what the specular does not take)
    ka      = kd + F0s                        all that a uniform surround (the ambient Ia) sends back
    kt      = b·(1 − m)·(1 − F0)·t           KHR_materials_transmission, with ior and fresnel: true
    ks      = F0s·(1 − g),  kr = F0s·g        F0s = F0·(1 − m) + b·m, the specular colour (metals: tinted)
    shininess = (1/r⁴ − 1)/2 in [1, 10⁴]     Beckmann α = r², Blinn-Phong n = 2/α² − 2 (Walter et al. 2007),
                                              and a Phong lobe about R is as wide as a Blinn one of 4× the exponent
    emission = emissiveFactor·emissiveStrength

so kd + ks + kr + kt ≤ 1 (the path tracer's energy bound) for every glTF material.

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
        metallic = doc.number(pbr, "metallicFactor", at_pbr, 1.0, 0.0, 1.0)
        rough = doc.number(pbr, "roughnessFactor", at_pbr, 1.0, 0.0, 1.0)
        ext = doc.obj(item, "extensions", at)
        ior = doc.number(doc.obj(ext, "KHR_materials_ior", f"{at}.extensions"), "ior",
                         f"{at}.extensions.KHR_materials_ior", 1.5, 0.0, 1e3)
        ior = 1.5 if ior == 0.0 else max(ior, 1.0)  # 0 and values below 1 are not physical dielectrics
        transmission = doc.number(doc.obj(ext, "KHR_materials_transmission", f"{at}.extensions"),
                                  "transmissionFactor", f"{at}.extensions.KHR_materials_transmission", 0.0, 0.0, 1.0)
        f0 = ((ior - 1.0) / (ior + 1.0)) ** 2
        dielectric = (1.0 - metallic) * (1.0 - f0)
        specular = f0 * (1.0 - metallic) + rgb * metallic
        g = (1.0 - rough) ** 2
        kd = rgb * dielectric * (1.0 - transmission)
        kt = rgb * dielectric * transmission
        mat = {"ka": kd + specular, "kd": kd, "ks": specular * (1.0 - g), "kr": specular * g,
               "shininess": shininess(rough)}
        if transmission > 0:
            mat.update(kt=kt, ior=ior, fresnel=True)
        strength = doc.number(doc.obj(ext, "KHR_materials_emissive_strength", f"{at}.extensions"),
                              "emissiveStrength", f"{at}.extensions.KHR_materials_emissive_strength", 1.0, 0.0)
        emission = np.clip(doc.numbers(item, "emissiveFactor", at, [0.0, 0.0, 0.0], 3), 0.0, None) * strength
        if emission.any():
            mat["emission"] = emission
        textures = []
        base_tex = self._texture(pbr, "baseColorTexture", at_pbr) if "baseColorTexture" in pbr else None
        if base_tex is not None:
            targets = [k for k in ("ka", "kd", "ks", "kr", "kt") if k in mat and np.any(mat[k] > 0)]
            targets = [k for k in targets if k != "kt"]  # lumos textures tint ka, kd, ks, kr (kt keeps b)
            if targets:
                tex = dict(base_tex[0], apply_to=targets)
                if not all(np.all(mat[k] == 1.0) for k in targets):  # replace equals multiply when they are 1
                    tex["mode"] = "multiply"
                textures.append(tex)
        if "emissiveTexture" in item and emission.any():
            emissive = self._texture(item, "emissiveTexture", at)
            if emissive is not None:
                textures.append(dict(emissive[0], apply_to=["emission"], mode="multiply"))
        self._alpha(item, at, mat, alpha, base_tex, textures)
        if textures:
            mat["texture"] = textures[0] if len(textures) == 1 else textures
        if "normalTexture" in item:
            normal = self._texture(item, "normalTexture", at)
            if normal is not None:
                info = doc.obj(item, "normalTexture", at)
                strength = doc.number(info, "scale", f"{at}.normalTexture", 1.0)
                bump = {k: v for k, v in normal[0].items() if k != "apply_to"}
                mat["bump"] = dict(bump, type="normal", strength=strength)
        for key in ("metallicRoughnessTexture",):
            if key in pbr:
                self.doc.warn(f"{at_pbr}.{key}: not read (lumos's material takes the metallic and roughness factors)")
        if "occlusionTexture" in item:
            self.doc.warn(f"{at}.occlusionTexture: not read (lumos computes occlusion where the method does)")
        return {k: (v.tolist() if isinstance(v, np.ndarray) else v) for k, v in mat.items()}

    def _alpha(self, item: dict, at: str, mat: dict, alpha: float, base_tex, textures: list) -> None:
        """alphaMode MASK: the base texture's alpha as an opacity cut-out (lumos cuts at 0.5); BLEND: the same
        cut-out, and the factor's alpha as a see-through share kt = 1 − α (ior 1) with the rest scaled by α."""
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
        if coverage < 1.0:
            for k in ("ka", "kd", "ks", "kr", "kt", "emission"):
                if k in mat:
                    mat[k] = np.asarray(mat[k]) * coverage
            mat["kt"] = np.asarray(mat.get("kt", 0.0)) + (1.0 - coverage)
            mat.setdefault("ior", 1.0)

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
        if coord != 0:
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

