"""What the local methods (raycast, whitted, raster) read of a principled material at a point whose textures set
its base colour, metallic or roughness there: the classic coefficients of `scene.materials.Principled.classic`,
computed from the point's b, m and r rather than from the factors alone.

    ka, kd, ks, kr, shininess = principled_classic(mat, b, m, r)

With g = (1 − r)² the share of the specular reflection that is a sharp mirror and F0s = F0·(1 − m) + b·m its
colour (F0 the row's dielectric MAT_F0, t its transmission, c its clear coat):

    kd = b·(1 − m)·(1 − F0)·(1 − t)·(1 − 0.04c)
    ks = F0s·(1 − 0.04c)·(1 − g)        kr = F0s·(1 − 0.04c)·g
    ka = kd, plus F0s·(1 − 0.04c) + 0.04c where no environment lights the model (MAT_KA_REFLECTS: the
    surroundings it reflects, read as ambient light)
    shininess = the Phong exponent as wide as GGX of width r² (`Principled.classic`'s `phong_exponent`)

and the coat's 0.04c added to kr (its roughness below 0.5) or to ks.
"""

from .jit import njit_inline
from .layout import MAT_CLEARCOAT, MAT_COAT_ALPHA, MAT_F0, MAT_KA_REFLECTS, MAT_TRANSMISSION


@njit_inline
def phong_exponent(alpha):
    """The Phong exponent whose lobe is about as wide as a GGX lobe of width α (`scene.materials.phong_exponent`,
    the same formula): in [1, 10⁴]."""
    if alpha < 0.0025:
        return 1e4
    return min(max(0.5 * (1.0 / (alpha * alpha) - 1.0), 1.0), 1e4)


@njit_inline
def principled_classic(mat, b, m, r):
    """(ka, kd, ks, kr, shininess) of the principled row `mat` with base colour b (r, g, b), metallic m and
    roughness r at the point (see the module doc)."""
    m = min(max(m, 0.0), 1.0)
    r = min(max(r, 0.0), 1.0)
    coat = 0.04 * mat[MAT_CLEARCOAT]
    smooth = mat[MAT_COAT_ALPHA] < 0.25  # clearcoat roughness below 0.5
    g = (1.0 - r) ** 2
    reflects = mat[MAT_KA_REFLECTS] != 0.0
    a0, d0, s0, r0 = _channel(mat, 0, b[0], m, g, coat, smooth, reflects)
    a1, d1, s1, r1 = _channel(mat, 1, b[1], m, g, coat, smooth, reflects)
    a2, d2, s2, r2 = _channel(mat, 2, b[2], m, g, coat, smooth, reflects)
    return (a0, a1, a2), (d0, d1, d2), (s0, s1, s2), (r0, r1, r2), phong_exponent(r * r)


@njit_inline
def _channel(mat, k, b, m, g, coat, smooth, reflects):
    """(ka, kd, ks, kr) of channel k."""
    f0 = mat[MAT_F0 + k]
    under = 1.0 - coat
    spec = (f0 * (1.0 - m) + b * m) * under
    kd = b * (1.0 - m) * (1.0 - f0) * under * (1.0 - mat[MAT_TRANSMISSION])
    ks = spec * (1.0 - g) + (0.0 if smooth else coat)
    kr = spec * g + (coat if smooth else 0.0)
    return (kd + spec + coat if reflects else kd), kd, ks, kr
