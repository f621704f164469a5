"""Materials' textures and bump maps → `tex_info` rows and one `tex_pixels` buffer (layout: `kernels.texture`).

    tex_info, tex_pixels = build_textures(materials)   # also sets each row's MAT_TEXTURE(_COUNT) / MAT_BUMP

Images are read once each with Pillow (two materials naming the same file share its texels). A colour texture
is decoded from sRGB to linear RGB (`tonemap.srgb_decode`); a bump map is data, not colour: its height is the
Rec. 709 luminance of the file's raw values scaled to [0, 1], not decoded; a normal map keeps its raw RGB; an
opacity texture keeps the image's alpha channel (its raw luminance when it has none) in all three channels.
Rows are stored bottom row first; a colour image, a height map or a normal map is followed by its mip-map levels
(`mip_levels`; every method that filters textures reads them: raster, raycast and whitted), an opacity image is not
(cut-outs are looked up at a point).

A material's textures are consecutive tex_info rows, in list order; a texture applied to `opacity` and to
colours as well becomes two rows (the colour one first), so that a row reads either colour or coverage.
"""

from __future__ import annotations

from collections import OrderedDict
from pathlib import Path

import numpy as np

from ..errors import LumosError
from ..kernels import layout as L
from ..kernels import texture as T

_KINDS = {"image": T.TEXTURE_IMAGE, "checker": T.TEXTURE_CHECKER, "stripes": T.TEXTURE_STRIPES,
          "noise": T.TEXTURE_NOISE, "normal": T.TEXTURE_IMAGE}
_WRAPS = {"repeat": T.WRAP_REPEAT, "clamp": T.WRAP_CLAMP}
_APPLY = {"ka": T.APPLY_KA, "kd": T.APPLY_KD, "ks": T.APPLY_KS, "kr": T.APPLY_KR, "emission": T.APPLY_EMISSION,
          "base_color": T.APPLY_BASE}
#: the data targets (alone in their texture): (apply bits, what the texels hold, the mode forced on them)
_DATA = {"metallic_roughness": (T.APPLY_METAL_ROUGH, "raw", None), "occlusion": (T.APPLY_KA, "red", "multiply")}
_MODES = {"replace": T.MODE_REPLACE, "multiply": T.MODE_MULTIPLY}
#: Rec. 709 / sRGB luminance weights
_LUMA = np.array([0.2126, 0.7152, 0.0722])


def build_textures(materials) -> tuple[np.ndarray, np.ndarray]:
    """Texture table of a `compile._Materials`: (tex_info float64 (n, TEX_SIZE), tex_pixels float32 (m, 3)).
    Each colour, height and normal image is followed by its mip-map levels: raster, raycast and whitted filter
    with them (unless `render.mipmap` is false, which the kernels decide, so the scene compiles the same for both);
    a pyramid costs a third more texels and a few ms per megatexel.

    Writes the first tex_info row of each material's textures (or -1) and their count into its MAT_TEXTURE and
    MAT_TEXTURE_COUNT columns, 1.0 into MAT_CUTOUT where one of them applies to opacity (0.0 elsewhere), and its
    bump map's row (or -1) into MAT_BUMP, in place in `materials.rows`, so call it before `materials.array()`.
    """
    table = _Table()
    for row, material in zip(materials.rows, materials.materials):
        row[L.MAT_TEXTURE], row[L.MAT_TEXTURE_COUNT], row[L.MAT_CUTOUT] = -1.0, 0.0, 0.0
        if material is None:  # an area light's emitter
            continue
        if material.textures:
            row[L.MAT_TEXTURE], row[L.MAT_TEXTURE_COUNT] = table.add_list(material.textures)
            row[L.MAT_CUTOUT] = float(any("opacity" in t.apply_to for t in material.textures))
        row[L.MAT_BUMP] = -1.0 if material.bump is None else table.add_bump(material.bump)
    return table.arrays()


class _Table:
    def __init__(self):
        self.infos: list[np.ndarray] = []
        self.lists: dict[tuple, tuple[int, int]] = {}  # ids of a material's texture models -> first row, count
        self.bumps: dict[int, int] = {}  # id(bump model) -> tex_info row
        self.images: dict[tuple[Path, str], tuple[int, int, int, int]] = {}  # (path, kind) -> offset, w, h, levels
        self.pixels: list[np.ndarray] = []
        self.n_pixels = 0

    def add_list(self, textures) -> tuple[int, int]:
        key = tuple(id(t) for t in textures)
        if key not in self.lists:
            first = len(self.infos)
            for tex in textures:
                data = _DATA.get(tex.apply_to[0])
                if data is not None:  # (scene.materials: a data texture applies to nothing else)
                    self.infos.append(self._row(tex, data[0], data[1], data[2]))
                    continue
                colour = sum(_APPLY[name] for name in set(tex.apply_to) if name != "opacity")
                if colour:
                    self.infos.append(self._row(tex, colour, "color"))
                if "opacity" in tex.apply_to:
                    self.infos.append(self._row(tex, T.APPLY_OPACITY, "alpha"))
            self.lists[key] = (first, len(self.infos) - first)
        return self.lists[key]

    def add_bump(self, bump) -> int:
        if id(bump) not in self.bumps:
            self.bumps[id(bump)] = len(self.infos)
            self.infos.append(self._row(bump, 0, "normal" if bump.type == "normal" else "height"))
        return self.bumps[id(bump)]

    def _row(self, tex, apply: int, kind: str, mode: str | None = None) -> np.ndarray:
        """One tex_info row; `kind` is what its texels hold: color, alpha, height, normal, raw (RGB) or red (the
        raw red in all three channels); `mode` overrides the texture's own."""
        info = np.zeros(T.TEX_SIZE)
        info[T.TEX_KIND] = _KINDS[tex.type]
        info[T.TEX_SCALE_U], info[T.TEX_SCALE_V] = tex.uv_scale
        info[T.TEX_SHIFT_U], info[T.TEX_SHIFT_V] = tex.offset
        info[T.TEX_WRAP] = _WRAPS[tex.wrap]
        info[T.TEX_APPLY] = apply
        if kind in ("height", "normal"):  # black to white: channel 0 of a height lookup is the height
            info[T.TEX_COLOR1 : T.TEX_COLOR1 + 3] = 1.0
            info[T.TEX_STRENGTH] = tex.strength
            info[T.TEX_BUMP_TYPE] = T.BUMP_NORMAL if kind == "normal" else T.BUMP_HEIGHT
        elif kind == "alpha":  # a pattern's coverage: the luminance of its colours
            info[T.TEX_COLOR0 : T.TEX_COLOR0 + 3] = float(np.dot(tex.colors[0], _LUMA))
            info[T.TEX_COLOR1 : T.TEX_COLOR1 + 3] = float(np.dot(tex.colors[1], _LUMA))
            info[T.TEX_MODE] = _MODES[tex.mode]
        else:
            info[T.TEX_COLOR0 : T.TEX_COLOR0 + 3] = tex.colors[0]
            info[T.TEX_COLOR1 : T.TEX_COLOR1 + 3] = tex.colors[1]
            info[T.TEX_MODE] = _MODES[mode or tex.mode]
        if tex.file is not None:
            info[T.TEX_OFFSET], info[T.TEX_WIDTH], info[T.TEX_HEIGHT], info[T.TEX_LEVELS] = self._image(tex, kind)
        return info

    def _image(self, tex, kind: str) -> tuple[int, int, int, int]:
        path = tex._path if tex._path is not None else Path(tex.file).expanduser().resolve()
        key = (path, kind)
        if key not in self.images:
            texels = load_texels(path, kind=kind)
            h, w = texels.shape[:2]
            # bottom row first: v = 0 at the bottom
            levels = mip_levels(texels[::-1]) if kind != "alpha" else [texels[::-1]]
            self.images[key] = (self.n_pixels, w, h, len(levels))
            for level in levels:
                self.pixels.append(level.reshape(-1, 3))
                self.n_pixels += level.shape[0] * level.shape[1]
        return self.images[key]

    def arrays(self) -> tuple[np.ndarray, np.ndarray]:
        info = np.array(self.infos, dtype=np.float64).reshape(-1, T.TEX_SIZE)
        pixels = np.concatenate(self.pixels) if self.pixels else np.zeros((0, 3))
        return np.ascontiguousarray(info), np.ascontiguousarray(pixels, dtype=np.float32)


def texture_mean(tex) -> np.ndarray:
    """The mean linear colour of a texture over its uv square (float64 (3,)): of an image's texels, or the two
    colours' mean for checker, stripes and noise (half the area each; the noise is symmetric about 0.5). For
    methods that cannot look a texture up per point (radiosity's patches)."""
    if tex.type == "image":
        path = tex._path if tex._path is not None else Path(tex.file).expanduser().resolve()
        return load_texels(path).reshape(-1, 3).astype(np.float64).mean(axis=0)
    return 0.5 * (np.asarray(tex.colors[0], np.float64) + np.asarray(tex.colors[1], np.float64))


def mean_coefficients(material) -> dict[str, np.ndarray]:
    """The material's classic ka, kd, ks, kr (`Material.classic`) and emission (float64 (3,) each) with each of
    its textures' mean colour applied in list order, replacing or multiplying as its `mode` says (opacity and the
    principled model's own targets are left out): what a method
    that cannot look textures up per point (radiosity) uses."""
    classic = material.classic()
    out = {name: np.asarray(classic[name], np.float64) for name in ("ka", "kd", "ks", "kr")}
    out["emission"] = np.asarray(material.emission, np.float64)
    for tex in material.textures:
        targets = [name for name in tex.apply_to if name in out]
        if not targets:
            continue
        mean = texture_mean(tex)
        for name in targets:
            out[name] = mean * out[name] if tex.mode == "multiply" else mean
    return out


def mip_levels(texels: np.ndarray) -> list[np.ndarray]:
    """The mip-map pyramid of (H, W, 3) texels, level 0 first: each next level max(1, w // 2) × max(1, h // 2),
    every texel the area-weighted mean of the texels of the level above that its footprint covers (a box
    filter; for even sizes, the mean of 2 × 2), down to 1 × 1."""
    levels = [np.asarray(texels, np.float32)]
    while levels[-1].shape[0] > 1 or levels[-1].shape[1] > 1:
        top = levels[-1]
        h, w = top.shape[:2]
        if h % 2 == 0 and w % 2 == 0:  # 2 × 2 means, summed as the two passes below sum them, 4× as fast
            pairs = top[0::2, 0::2].astype(np.float64) + top[1::2, 0::2]
            levels.append((0.25 * (pairs + (top[0::2, 1::2].astype(np.float64) + top[1::2, 1::2]))).astype(np.float32))
            continue
        top = top.astype(np.float64)
        top = _shrink(top, max(1, h // 2), axis=0)
        levels.append(_shrink(top, max(1, w // 2), axis=1).astype(np.float32))
    return levels


def _shrink(a: np.ndarray, m: int, axis: int) -> np.ndarray:
    """`a` box-filtered along `axis` from n to m <= n samples: output i averages the input over
    [i·n/m, (i + 1)·n/m), each input sample weighted by its overlap (at most n/m + 1 of them)."""
    n = a.shape[axis]
    if m == n:
        return a
    if n == 2 * m:  # the mean of each pair (the same sum as below, without its taps of weight 0)
        a = np.moveaxis(a, axis, 0)
        return np.moveaxis(0.5 * a[0::2] + 0.5 * a[1::2], 0, axis)
    lo = np.arange(m) * (n / m)
    taps = int(np.ceil(n / m)) + 1
    j = np.floor(lo).astype(np.int64)[:, None] + np.arange(taps)[None, :]  # (m, taps) candidate inputs
    weight = np.clip(np.minimum(lo[:, None] + n / m, j + 1) - np.maximum(lo[:, None], j), 0.0, None)
    weight /= weight.sum(axis=1, keepdims=True)
    a = np.moveaxis(a, axis, 0)
    out = np.zeros((m,) + a.shape[1:])
    for k in range(taps):
        out += weight[:, k].reshape((m,) + (1,) * (a.ndim - 1)) * a[np.minimum(j[:, k], n - 1)]
    return np.moveaxis(out, 0, axis)


#: decoded images kept for the next compile in this process (a sheet, an animation, the preview compile the same
#: scene again), by file, modification time, size and kind, up to this many bytes (oldest dropped first)
TEXEL_CACHE_BYTES = 512 << 20
_texel_cache: OrderedDict = OrderedDict()


def load_texels(path, bump: bool = False, kind: str = "color") -> np.ndarray:
    """float32 (H, W, 3) texels of an image file, top row first, by `kind`: `color`, linear RGB decoded from
    sRGB; `height` (or `bump=True`), the luminance of the raw values in [0, 1], repeated in all three channels;
    `normal`, the raw RGB in [0, 1]; `alpha`, the raw alpha channel, or the raw luminance of an image without
    one, repeated in all three channels; `raw`, the raw RGB (a glTF metallic–roughness map); `red`, the raw red
    in all three (a glTF occlusion map). Only `alpha` reads the alpha channel. Read-only: the array may be
    the one an earlier call decoded (`TEXEL_CACHE_BYTES`)."""
    kind = "height" if bump else kind
    try:
        stat = Path(path).stat()
    except OSError as exc:
        reason = exc.strerror or type(exc).__name__
        raise LumosError(f"cannot read image {str(path)!r}: {reason}") from None
    key = (str(Path(path).resolve()), stat.st_mtime_ns, stat.st_size, kind)
    if key in _texel_cache:
        _texel_cache.move_to_end(key)
        return _texel_cache[key]
    texels = _decode(path, kind)
    texels.flags.writeable = False
    _texel_cache[key] = texels
    while sum(a.nbytes for a in _texel_cache.values()) > TEXEL_CACHE_BYTES and len(_texel_cache) > 1:
        _texel_cache.popitem(last=False)
    return texels


def _srgb_table() -> np.ndarray:
    """float32 (256,): the linear value of each 8-bit sRGB code (exactly what `srgb_decode` gives, as a table)."""
    from ..tonemap import srgb_decode

    return srgb_decode(np.arange(256) / 255.0).astype(np.float32)


def _decode(path, kind: str) -> np.ndarray:
    """`load_texels` without the cache."""
    from PIL import Image as PILImage

    from ..tonemap import srgb_decode

    alpha = None
    codes = None  # 8-bit RGB, decoded through a table when the texels are colours
    try:
        with PILImage.open(path) as img:
            img.load()
            if img.mode in ("I;16", "I;16B", "I;16L", "I"):  # 16-bit greyscale PNG
                raw = np.asarray(img, dtype=np.float64) / 65535.0
                raw = np.repeat(np.clip(raw, 0.0, 1.0)[..., None], 3, axis=2)
            elif img.mode == "F":
                raw = np.repeat(np.asarray(img, dtype=np.float64)[..., None], 3, axis=2)
            elif kind == "color":
                codes = np.asarray(img.convert("RGB"))
            else:
                raw = np.asarray(img.convert("RGB"), dtype=np.float64) / 255.0
                if kind == "alpha" and ("A" in img.getbands() or "transparency" in img.info):
                    alpha = np.asarray(img.convert("RGBA"), dtype=np.float64)[..., 3] / 255.0
    except (OSError, ValueError, SyntaxError) as exc:  # PIL raises all three on bad files
        reason = " ".join(str(exc).split()) or type(exc).__name__
        raise LumosError(f"cannot read image {str(path)!r}: {reason}") from None
    if codes is not None:
        return _srgb_table()[codes]
    if kind in ("height", "alpha"):
        value = raw @ _LUMA if alpha is None else alpha
        return np.repeat(value[..., None], 3, axis=2).astype(np.float32)
    if kind in ("normal", "raw"):
        return raw.astype(np.float32)
    if kind == "red":
        return np.repeat(raw[..., :1], 3, axis=2).astype(np.float32)
    return srgb_decode(raw).astype(np.float32)
