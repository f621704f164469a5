"""Regenerate the example textures of this folder (deterministic; Pillow + NumPy):

    python examples/data/textures/make_textures.py

planet.png    256×128 sRGB colour map in latitude–longitude layout (u = longitude, v = latitude, north at the top):
              oceans, continents from fractal noise, deserts, forests, polar ice. Seamless across u = 0 / 1.
bumps.png     128×128 8-bit greyscale height map (raw values, not colour): round craters on a rolling ground,
              seamless in both directions.
checker.png   256×256 sRGB checkerboard of 4×4 tiles, cream and slate, with a thin dark grout line: a floor whose
              fine detail aliases into moiré towards the horizon unless the renderer filters it (mip-mapping).
"""

from pathlib import Path

import numpy as np
from PIL import Image

HERE = Path(__file__).resolve().parent


def fbm(x, y, octaves, period_x, period_y, seed):
    """Fractal value noise in [0, 1] at arrays x, y; the lattice of octave k repeats every period·2**k cells."""
    rng = np.random.default_rng(seed)
    total = np.zeros_like(x)
    amplitude, norm = 1.0, 0.0
    for k in range(octaves):
        px, py = period_x * 2**k, period_y * 2**k
        grid = rng.random((py + 1, px + 1))
        grid[:, -1] = grid[:, 0]
        grid[-1, :] = grid[0, :]
        gx, gy = x * 2**k, y * 2**k
        ix, iy = np.floor(gx).astype(int) % px, np.floor(gy).astype(int) % py
        fx, fy = gx - np.floor(gx), gy - np.floor(gy)
        fx, fy = fx * fx * (3 - 2 * fx), fy * fy * (3 - 2 * fy)
        a = grid[iy, ix] + fx * (grid[iy, ix + 1] - grid[iy, ix])
        b = grid[iy + 1, ix] + fx * (grid[iy + 1, ix + 1] - grid[iy + 1, ix])
        total += amplitude * (a + fy * (b - a))
        norm += amplitude
        amplitude *= 0.5
    return total / norm


def planet(width=256, height=128):
    u = (np.arange(width) + 0.5) / width
    lat = 0.5 - (np.arange(height) + 0.5) / height  # +0.5 at the top row (north), -0.5 at the bottom
    U, LAT = np.meshgrid(u, lat)
    land = fbm(U * 4, (LAT + 0.5) * 2, 5, 4, 2, seed=7)
    moist = fbm(U * 4, (LAT + 0.5) * 2, 3, 4, 2, seed=11)
    ocean = np.array([0.02, 0.12, 0.40]) + (land[..., None] - 0.3) * np.array([0.0, 0.2, 0.4])
    forest = np.array([0.10, 0.35, 0.08])
    desert = np.array([0.75, 0.62, 0.35])
    ground = np.where((moist > 0.5)[..., None], forest, desert) * (0.8 + 0.4 * land[..., None])
    rgb = np.where((land > np.quantile(land, 0.62))[..., None], ground, ocean)
    ice = np.abs(LAT) > 0.40 - 0.05 * moist
    rgb[ice] = (0.92, 0.94, 0.97)
    return Image.fromarray(np.rint(255 * np.clip(rgb, 0, 1)).astype(np.uint8), mode="RGB")


def bumps(size=128):
    c = (np.arange(size) + 0.5) / size
    X, Y = np.meshgrid(c, c)
    h = 0.5 + 0.3 * (fbm(X * 4, Y * 4, 4, 4, 4, seed=3) - 0.5)
    rng = np.random.default_rng(5)
    for cx, cy, r in zip(rng.random(12), rng.random(12), 0.04 + 0.08 * rng.random(12)):
        dx = (X - cx + 0.5) % 1.0 - 0.5  # distances on the torus: the map tiles
        dy = (Y - cy + 0.5) % 1.0 - 0.5
        d = np.sqrt(dx * dx + dy * dy) / r
        bowl = np.where(d < 1, -0.25 * (1 - d * d), 0.0)
        rim = 0.12 * np.exp(-((d - 1.0) / 0.15) ** 2)
        h += bowl + rim
    return Image.fromarray(np.rint(255 * np.clip(h, 0, 1)).astype(np.uint8), mode="L")


def checker(size=256, tiles=4):
    c = np.arange(size)
    X, Y = np.meshgrid(c, c)
    cell = size // tiles
    odd = ((X // cell) + (Y // cell)) % 2 == 1
    rgb = np.where(odd[..., None], np.array([0.23, 0.27, 0.33]), np.array([0.86, 0.82, 0.72]))
    grout = (X % cell < 3) | (Y % cell < 3)
    rgb[grout] = (0.08, 0.08, 0.09)
    return Image.fromarray(np.rint(255 * rgb).astype(np.uint8), mode="RGB")


if __name__ == "__main__":
    planet().save(HERE / "planet.png", optimize=True)
    bumps().save(HERE / "bumps.png", optimize=True)
    checker().save(HERE / "checker.png", optimize=True)
