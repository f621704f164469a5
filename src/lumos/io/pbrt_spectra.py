"""pbrt-v4's spectra as lumos's linear sRGB: sampled spectra, blackbodies and pbrt's named spectra.

    reflectance_rgb(lambdas, values)   # a reflectance (albedo) spectrum, lit by D65: a flat 1 is (1, 1, 1)
    illuminant_rgb(lambdas, values)    # an emission spectrum, scaled to luminance Y = 1 (as pbrt-v4 does)
    blackbody_rgb(6500)                # a blackbody's colour at luminance 1
    fresnel_f0(eta, k)                 # a conductor's reflectance at normal incidence, from its η and k spectra
    NAMED_METALS["Au"], NAMED_GLASSES["glass-BK7"], NAMED_ILLUMINANTS["stdillum-A"]

How: the CIE 1931 2° colour matching functions x̄, ȳ, z̄ and the D65 illuminant, sampled every 10 nm from 380 to
780 nm (the CIE's tables, here as pbrt-v4 copies them in src/pbrt/util/spectrum.cpp) and interpolated to every
nm, integrate a spectrum into XYZ; the standard XYZ → linear sRGB (D65 white) matrix, calibrated so that D65
itself comes out exactly (1, 1, 1), gives RGB. A reflectance is integrated under D65 and divided by D65's Y (so
white stays white); an emission spectrum is divided by its own Y, since pbrt-v4 scales every spectral light to
1 nit before its `scale` and `power` apply (lights.cpp: `scale /= SpectrumToPhotometric(L)`). A sampled
spectrum (pairs λ, value) is linear between its samples and 0 outside them, as pbrt's PiecewiseLinearSpectrum.

The named tables below were derived with these functions from pbrt-v4's tabulated data
(tests/data/pbrt/derive_spectra.py regenerates them): a metal's head-on reflectance F0(λ) =
((η − 1)² + k²)/((η + 1)² + k²) integrated as a reflectance; a glass's η at 550 nm (lumos's `ior` is one
number: no dispersion); an illuminant's colour at luminance 1.
"""

from __future__ import annotations

import math

import numpy as np

#: the wavelengths of the tables, nm
GRID = np.arange(380.0, 781.0, 10.0)
#: CIE 1931 2° x̄, ȳ, z̄ at GRID
_CMF = np.array([
    [0.001368, 0.000039, 0.00645], [0.004243, 0.00012, 0.02005], [0.01431, 0.000396, 0.06785],
    [0.04351, 0.00121, 0.2074], [0.13438, 0.004, 0.6456], [0.2839, 0.0116, 1.3856], [0.34828, 0.023, 1.74706],
    [0.3362, 0.038, 1.77211], [0.2908, 0.06, 1.6692], [0.19536, 0.09098, 1.28764], [0.09564, 0.13902, 0.81295],
    [0.03201, 0.20802, 0.46518], [0.0049, 0.323, 0.272], [0.0093, 0.503, 0.1582], [0.06327, 0.71, 0.07825],
    [0.1655, 0.862, 0.04216], [0.2904, 0.954, 0.0203], [0.43345, 0.99495, 0.00875], [0.5945, 0.995, 0.0039],
    [0.7621, 0.952, 0.0021], [0.9163, 0.87, 0.00165], [1.0263, 0.757, 0.0011], [1.0622, 0.631, 0.0008],
    [1.0026, 0.503, 0.00034], [0.85445, 0.381, 0.00019], [0.6424, 0.265, 0.00005], [0.4479, 0.175, 0.00002],
    [0.2835, 0.107, 0.0], [0.1649, 0.061, 0.0], [0.0874, 0.032, 0.0], [0.04677, 0.017, 0.0],
    [0.0227, 0.00821, 0.0], [0.011359, 0.004102, 0.0], [0.00579, 0.002091, 0.0], [0.002899, 0.001047, 0.0],
    [0.00144, 0.00052, 0.0], [0.00069, 0.000249, 0.0], [0.000332, 0.00012, 0.0], [0.000166, 0.00006, 0.0],
    [0.000083, 0.00003, 0.0], [0.000042, 0.000015, 0.0]])
#: CIE D65 relative spectral power at GRID (100 at 560 nm)
_D65 = np.array([
    49.975, 54.648, 82.755, 91.486, 93.432, 86.682, 104.865, 117.008, 117.812, 114.861, 115.923, 108.811,
    109.354, 107.802, 104.79, 107.689, 104.405, 104.046, 100.0, 96.334, 95.788, 88.686, 90.006, 89.599, 87.699,
    83.289, 83.699, 80.027, 80.215, 82.278, 78.284, 69.721, 71.609, 74.349, 61.604, 69.886, 75.087, 63.593,
    46.418, 66.805, 63.383])
#: XYZ → linear sRGB (IEC 61966-2-1, D65 white)
_SRGB_FROM_XYZ = np.array([[3.2404542, -1.5371385, -0.4985314],
                           [-0.9692660, 1.8760108, 0.0415560],
                           [0.0556434, -0.2040259, 1.0572252]])
#: the integration grid: every nm, the tables interpolated linearly (so spiky spectra, fluorescent lamps, are not
#: aliased by the 10 nm tables)
_FINE = np.arange(380.0, 780.5, 1.0)
_CMF_FINE = np.stack([np.interp(_FINE, GRID, _CMF[:, i]) for i in range(3)], axis=1)
_D65_FINE = np.interp(_FINE, GRID, _D65)
_D65_XYZ = (_CMF_FINE * _D65_FINE[:, None]).sum(axis=0) / (_CMF_FINE[:, 1] * _D65_FINE).sum()
#: per-channel calibration: the 10 nm tables' D65 maps to exactly (1, 1, 1)
_CALIBRATION = 1.0 / (_SRGB_FROM_XYZ @ _D65_XYZ)

#: pbrt-v4's named conductors ("metal-<name>-eta" / "-k"): their head-on reflectance F0, linear sRGB
NAMED_METALS = {
    "Ag": (0.9715, 0.9599, 0.9153),
    "Al": (0.9132, 0.9215, 0.9244),
    "Au": (1, 0.7816, 0.3439),
    "Cu": (0.9545, 0.638, 0.5381),
    "CuZn": (0.9097, 0.7778, 0.4234),
    "MgO": (0.072, 0.0731, 0.0749),
    "TiO2": (0.2322, 0.2446, 0.2727),
}
#: pbrt-v4's named glasses: η at 550 nm
NAMED_GLASSES = {
    "glass-BK7": 1.5185,
    "glass-BAF10": 1.6731,
    "glass-FK51A": 1.4878,
    "glass-LASF9": 1.8558,
    "glass-F5": 1.6771,
    "glass-F10": 1.7336,
    "glass-F11": 1.7911,
}
#: pbrt-v4's named illuminants: their colour at luminance 1, linear sRGB
NAMED_ILLUMINANTS = {
    "stdillum-A": (1.8443, 0.8261, 0.2337),
    "stdillum-D50": (1.0869, 0.9994, 0.7499),
    "stdillum-D65": (1.0000, 1.0000, 1.0000),
    "stdillum-F1": (0.9515, 1.0206, 0.9391),
    "stdillum-F2": (1.3360, 0.9445, 0.5593),
    "stdillum-F3": (1.5714, 0.8928, 0.3775),
    "stdillum-F4": (1.8000, 0.8363, 0.2636),
    "stdillum-F5": (0.9132, 1.0373, 0.8863),
    "stdillum-F6": (1.3126, 0.9591, 0.4833),
    "stdillum-F7": (0.9992, 1.0010, 0.9925),
    "stdillum-F8": (1.1763, 0.9761, 0.7163),
    "stdillum-F9": (1.3756, 0.9321, 0.5657),
    "stdillum-F10": (1.1724, 0.9775, 0.7140),
    "stdillum-F11": (1.4055, 0.9270, 0.5278),
    "stdillum-F12": (1.7597, 0.8478, 0.2684),
    "illum-acesD60": (1.0470, 0.9945, 0.9156),
}


def on_grid(lambdas, values, grid: np.ndarray = _FINE) -> np.ndarray:
    """A sampled spectrum (increasing wavelengths in nm, values) at `grid` (every nm from 380 to 780): linear
    between samples, 0 outside them."""
    lam = np.asarray(lambdas, dtype=np.float64)
    val = np.asarray(values, dtype=np.float64)
    return np.interp(grid, lam, val, left=0.0, right=0.0)


def _rgb(xyz: np.ndarray) -> tuple[float, float, float]:
    rgb = _CALIBRATION * (_SRGB_FROM_XYZ @ xyz)
    return tuple(float(round(max(c, 0.0), 6)) for c in rgb)


def reflectance_rgb(lambdas, values) -> tuple[float, float, float]:
    """The linear sRGB of a reflectance spectrum seen under D65 (a flat spectrum of value a gives (a, a, a))."""
    s = on_grid(lambdas, values)
    return _rgb((_CMF_FINE * (s * _D65_FINE)[:, None]).sum(axis=0) / (_CMF_FINE[:, 1] * _D65_FINE).sum())


def illuminant_rgb(lambdas, values) -> tuple[float, float, float]:
    """The linear sRGB of an emission spectrum scaled to luminance Y = 1 (black when it has no visible light)."""
    s = on_grid(lambdas, values)
    y = float((_CMF_FINE[:, 1] * s).sum())
    if y <= 0.0:
        return (0.0, 0.0, 0.0)
    return _rgb((_CMF_FINE * s[:, None]).sum(axis=0) / y)


def blackbody_rgb(kelvin: float) -> tuple[float, float, float]:
    """The colour of a blackbody at `kelvin`, at luminance 1 (Planck's law; pbrt-v4's "blackbody" spectra are
    normalised and its lights scaled to 1 nit, so only the colour remains)."""
    c, h, kb = 299792458.0, 6.62606957e-34, 1.3806488e-23
    lam = _FINE * 1e-9
    radiance = (2 * h * c * c) / (lam ** 5 * (np.exp(np.minimum(h * c / (lam * kb * kelvin), 700.0)) - 1.0))
    return illuminant_rgb(_FINE, radiance)


def fresnel_f0(eta: np.ndarray, k: np.ndarray) -> np.ndarray:
    """A conductor's reflectance at normal incidence, ((η − 1)² + k²)/((η + 1)² + k²), element-wise."""
    eta, k = np.asarray(eta, dtype=np.float64), np.asarray(k, dtype=np.float64)
    return ((eta - 1.0) ** 2 + k * k) / ((eta + 1.0) ** 2 + k * k)


def luminance(rgb) -> float:
    """Y of a linear sRGB colour."""
    return 0.2126 * rgb[0] + 0.7152 * rgb[1] + 0.0722 * rgb[2]


def kelvin_ok(kelvin: float) -> bool:
    return math.isfinite(kelvin) and kelvin > 0.0
