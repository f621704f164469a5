"""Mitsuba 3's numbers that a scene file names instead of giving: spectra → RGB, named IORs, conductor presets.

    spectrum_rgb(wavelengths, values, emitter=False)   a `<spectrum>` of wavelength:value pairs as RGB
    uniform_spectrum_rgb(value, emitter=False)         a `<spectrum value="v"/>` as RGB
    named_ior("bk7")                                   1.5046 (Mitsuba's table, case-insensitive), or None
    CONDUCTORS["Au"]                                   ((η_r, η_g, η_b), (k_r, k_g, k_b)) of the preset

Everything here is what Mitsuba 3's RGB variants (`scalar_rgb`, `llvm_ad_rgb`) compute, so that a scene reads as
Mitsuba renders it in RGB mode:

- **Spectra** (`src/core/properties.cpp`, `spectrum_list_to_srgb` in `src/core/spectrum.cpp`): the piecewise
  linear spectrum is integrated against the CIE 1931 2° colour matching functions (tabulated every 5 nm from 360
  to 830 nm, linearly interpolated) by a 1,000-point Riemann sum over [360, 830] nm (points outside the given
  wavelengths count 0), normalised so that a unit spectrum has luminance Y = 1, and taken from XYZ to linear
  sRGB (Rec. 709 primaries, D65 white). A reflectance (not an emitter's radiance) is first multiplied by the
  CIE D65 illuminant (normalised the same way), so that a flat 1 is white, and is clamped to [0, 1]; an
  emitter's spectrum is not weighted, and only negative channels are clamped. A uniform spectrum is its value on
  every channel, except for an emitter, where Mitsuba takes it as XYZ = (v, v, v): v·(1.2048, 0.9483, 0.9089).
- **Named IORs** (`include/mitsuba/render/ior.h`): Hecht's table at ~589 nm.
- **Conductor presets** (`material="Au"` …): Mitsuba's measured η and k spectra (`data/ior/<name>.eta.spd`,
  `.k.spd`, shipped with Mitsuba 3.9.1), each converted by the same integral without the D65 weight and
  without clamping to [0, 1] (`complex_ior_from_file`), as Mitsuba's RGB variants load them. The table below
  was computed so from those files; tests/io/test_mitsuba.py checks it against Mitsuba where it is installed.
"""

from __future__ import annotations

import numpy as np

#: the CIE 1931 2° colour matching functions x̄, ȳ, z̄ at 360, 365, …, 830 nm (Mitsuba's cie1931_tbl)
CIE_MIN, CIE_MAX, CIE_SAMPLES = 360.0, 830.0, 95
#: 1 / ∫ȳ dλ of the tabulated curves: a unit spectrum has luminance 1
CIE_Y_NORMALIZATION = 1.0 / 106.7502593994140625
#: 1 / the luminance of the tabulated D65 illuminant (relative to its power at 560 nm)
D65_NORMALIZATION = 1.0 / 98.99741751876255
#: CIE XYZ → linear sRGB (Rec. 709 primaries, D65 white), Mitsuba's xyz_to_srgb
XYZ_TO_SRGB = np.array([[3.240479, -1.537150, -0.498535],
                        [-0.969256, 1.875991, 0.041556],
                        [0.055648, -0.204043, 1.057311]])
_STEPS = 1000


def spectrum_rgb(wavelengths, values, *, d65: bool = True, bounded: bool = True) -> tuple[float, float, float]:
    """Linear sRGB of the piecewise linear spectrum through (wavelengths[i], values[i]) (nm, increasing; at least
    two), as Mitsuba's `spectrum_list_to_srgb`: a reflectance with `d65` and `bounded` (clamped to [0, 1]), an
    emitter's radiance without either (negative channels clamped to 0), a conductor preset's η or k neither."""
    wl, v = np.asarray(wavelengths, np.float64), np.asarray(values, np.float64)
    w = CIE_MIN + np.arange(_STEPS) / (_STEPS - 1) * (CIE_MAX - CIE_MIN)
    w = w[(w >= wl[0]) & (w <= wl[-1])]
    i = np.clip(np.searchsorted(wl, w, side="right") - 1, 0, len(wl) - 2)
    w0, w1 = wl[i], wl[i + 1]
    value = ((w - w1) * v[i] + (w0 - w) * v[i + 1]) / (w0 - w1)
    if d65:
        value = value * _tabulated(w, _D65) * D65_NORMALIZATION
    xyz = np.array([np.sum(_tabulated(w, table) * value) for table in (_CIE_X, _CIE_Y, _CIE_Z)])
    rgb = XYZ_TO_SRGB @ (xyz * (CIE_MAX - CIE_MIN) * CIE_Y_NORMALIZATION / _STEPS)
    rgb = np.clip(rgb, 0.0, 1.0) if bounded else np.maximum(rgb, 0.0)
    return tuple(float(c) for c in rgb)


def uniform_spectrum_rgb(value: float, emitter: bool = False) -> tuple[float, float, float]:
    """A uniform spectrum's RGB: grey, except for an emitter, whose flat spectrum Mitsuba's RGB variants read as
    XYZ = (v, v, v) (the colour a flat spectrum has under sRGB's D65 white: slightly purple)."""
    if not emitter:
        return (float(value),) * 3
    return tuple(float(c) for c in XYZ_TO_SRGB @ np.full(3, float(value)))


def _tabulated(w: np.ndarray, table) -> np.ndarray:
    """A 5-nm table (360–830 nm) linearly interpolated at the wavelengths w (Mitsuba's cie1931_xyz, cie_d65)."""
    t = (w - CIE_MIN) * ((CIE_SAMPLES - 1) / (CIE_MAX - CIE_MIN))
    i0 = np.clip(t.astype(np.int64), 0, CIE_SAMPLES - 2)
    frac = t - i0
    tab = np.asarray(table, np.float64)
    return (1.0 - frac) * tab[i0] + frac * tab[i0 + 1]


def read_spd(path) -> tuple[list[float], list[float]]:
    """The (wavelengths, values) of a Mitsuba `.spd` file: one `wavelength value` pair a line, `#` comments.
    Raises ValueError (with the line) for a line that is not two numbers."""
    wavelengths, values = [], []
    with open(path, encoding="utf-8", errors="replace") as f:
        for number, line in enumerate(f, 1):
            line = line.split("#", 1)[0].strip()
            if not line:
                continue
            parts = line.split()
            try:
                w, v = float(parts[0]), float(parts[1])
            except (ValueError, IndexError):
                raise ValueError(f"line {number}: expected 'wavelength value', got {line[:40]!r}") from None
            wavelengths.append(w)
            values.append(v)
    return wavelengths, values


def named_ior(name: str) -> float | None:
    """Mitsuba's IOR of a named material ("bk7", "water", "air"…; case-insensitive), or None."""
    return IORS.get(name.strip().lower())


def conductor_reflectance(eta, k) -> tuple[float, float, float]:
    """The normal-incidence Fresnel reflectance of a conductor, per channel: ((η−1)² + k²)/((η+1)² + k²)."""
    eta, k = np.asarray(eta, np.float64), np.asarray(k, np.float64)
    return tuple(float(c) for c in ((eta - 1) ** 2 + k * k) / ((eta + 1) ** 2 + k * k))


#: Mitsuba's named indices of refraction (ior.h: Hecht, Optics, 4th ed., 0–20 °C, ~589 nm)
IORS = {
    "vacuum": 1.0, "helium": 1.000036, "hydrogen": 1.000132, "air": 1.000277, "carbon dioxide": 1.00045,
    "water": 1.3330, "acetone": 1.36, "ethanol": 1.361, "carbon tetrachloride": 1.461, "glycerol": 1.4729,
    "benzene": 1.501, "silicone oil": 1.52045, "bromine": 1.661,
    "water ice": 1.31, "fused quartz": 1.458, "pyrex": 1.470, "acrylic glass": 1.49, "polypropylene": 1.49,
    "bk7": 1.5046, "sodium chloride": 1.544, "amber": 1.55, "pet": 1.5750, "diamond": 2.419,
}

#: conductor presets: name -> ((eta_r, eta_g, eta_b), (k_r, k_g, k_b)), from Mitsuba 3.9.1's data/ior/*.spd
CONDUCTORS = {
    "Ag": ((0.155276, 0.116728, 0.138388), (4.82835, 3.12222, 2.1469)),
    "Al": ((1.6575, 0.880405, 0.521244), (9.22381, 6.2695, 4.837)),
    "AlAs": ((3.6053, 3.23294, 2.21632), (0.000679437, 0, 0.00751271)),
    "AlAs_palik": ((3.6053, 3.23294, 2.21632), (0.000679437, 0, 0.00751271)),
    "AlSb": ((0, 4.13937, 4.66925), (0, 0.0940091, 1.30057)),
    "AlSb_palik": ((0, 4.13937, 4.66925), (0, 0.0940091, 1.30057)),
    "Au": ((0.143036, 0.375307, 1.44205), (3.983, 2.38556, 1.60336)),
    "Be": ((4.18501, 3.18503, 2.78406), (3.83547, 3.01012, 2.86899)),
    "Be_palik": ((4.18501, 3.18503, 2.78406), (3.83547, 3.01012, 2.86899)),
    "Cr": ((4.36967, 2.91651, 1.6549), (5.20655, 4.23131, 3.7547)),
    "CsI": ((2.1449, 1.70232, 1.66243), (0, 0, 0)),
    "CsI_palik": ((2.1449, 1.70232, 1.66243), (0, 0, 0)),
    "Cu": ((0.201006, 0.923749, 1.10222), (3.91326, 2.45305, 2.14209)),
    "Cu2O": ((3.55177, 2.94987, 2.75188), (0.114207, 0.193897, 0.606134)),
    "Cu2O_palik": ((3.55177, 2.94987, 2.75188), (0.114207, 0.193897, 0.606134)),
    "CuO": ((3.24754, 2.44781, 2.21022), (0.52109, 0.570031, 0.722179)),
    "CuO_palik": ((3.24754, 2.44781, 2.21022), (0.52109, 0.570031, 0.722179)),
    "Cu_palik": ((0.213229, 0.919715, 1.10241), (3.92187, 2.45733, 2.13658)),
    "Hg": ((2.39894, 1.44003, 0.90957), (6.32759, 4.37192, 3.42176)),
    "HgTe": ((4.77904, 3.2312, 2.6599), (1.63161, 1.58081, 1.72929)),
    "HgTe_palik": ((4.77904, 3.2312, 2.6599), (1.63161, 1.58081, 1.72929)),
    "Hg_palik": ((2.39894, 1.44003, 0.90957), (6.32759, 4.37192, 3.42176)),
    "Ir": ((3.0863, 2.08219, 1.61791), (5.59215, 4.06709, 3.26731)),
    "Ir_palik": ((3.0863, 2.08219, 1.61791), (5.59215, 4.06709, 3.26731)),
    "K": ((0.0640432, 0.0464098, 0.0381849), (2.1042, 1.34894, 0.913126)),
    "K_palik": ((0.0640432, 0.0464098, 0.0381849), (2.1042, 1.34894, 0.913126)),
    "Li": ((0.265791, 0.195618, 0.220949), (3.54016, 2.31112, 1.66861)),
    "Li_palik": ((0.265791, 0.195618, 0.220949), (3.54016, 2.31112, 1.66861)),
    "MgO": ((2.08958, 1.65072, 1.59488), (4.3327e-12, 0, 2.49865e-11)),
    "MgO_palik": ((2.08958, 1.65072, 1.59488), (4.3327e-12, 0, 2.49865e-11)),
    "Mo": ((4.48397, 3.52513, 2.77631), (4.11144, 3.42083, 3.15061)),
    "Mo_palik": ((4.48397, 3.52513, 2.77631), (4.11144, 3.42083, 3.15061)),
    "Na_palik": ((0.0602694, 0.0561409, 0.0619884), (3.17927, 2.11249, 1.57904)),
    "Nb": ((3.42007, 2.79009, 2.39563), (3.44139, 2.73767, 2.57975)),
    "Nb_palik": ((3.42007, 2.79009, 2.39563), (3.44139, 2.73767, 2.57975)),
    "Ni_palik": ((2.3673, 1.66337, 1.46708), (4.49881, 3.05015, 2.34544)),
    "Rh": ((2.58579, 1.86022, 1.55426), (6.78226, 4.70299, 3.97607)),
    "Rh_palik": ((2.58579, 1.86022, 1.55426), (6.78226, 4.70299, 3.97607)),
    "Se": ((4.05831, 2.84293, 2.82085), (0.75405, 0.638444, 0.521807)),
    "Se-e": ((5.72285, 4.16574, 4.08134), (0.871136, 1.10516, 1.56532)),
    "Se-e_palik": ((5.72285, 4.16574, 4.08134), (0.871136, 1.10516, 1.56532)),
    "Se_palik": ((4.05831, 2.84293, 2.82085), (0.75405, 0.638444, 0.521807)),
    "SiC": ((3.17234, 2.52597, 2.47937), (7.53766e-07, 0, 1.01925e-05)),
    "SiC_palik": ((3.17234, 2.52597, 2.47937), (7.53766e-07, 0, 1.01925e-05)),
    "SnTe": ((4.52425, 1.98164, 1.28159), (0, 0, 0)),
    "SnTe_palik": ((4.52425, 1.98164, 1.28159), (0, 0, 0)),
    "Ta": ((2.06272, 2.39294, 2.62793), (2.40836, 1.74149, 1.94703)),
    "Ta_palik": ((2.06272, 2.39294, 2.62793), (2.40836, 1.74149, 1.94703)),
    "Te": ((7.39023, 4.4821, 2.63711), (3.25602, 3.52706, 3.29205)),
    "Te-e": ((7.50891, 4.29643, 2.36999), (5.58393, 4.9472, 3.99759)),
    "Te-e_palik": ((7.50891, 4.29643, 2.36999), (5.58393, 4.9472, 3.99759)),
    "Te_palik": ((7.39023, 4.4821, 2.63711), (3.25602, 3.52706, 3.29205)),
    "ThF4": ((1.83071, 1.44223, 1.38765), (0, 0, 0)),
    "ThF4_palik": ((1.83071, 1.44223, 1.38765), (0, 0, 0)),
    "TiC": ((3.70053, 2.83742, 2.58229), (3.26564, 2.35159, 2.17279)),
    "TiC_palik": ((3.70053, 2.83742, 2.58229), (3.26564, 2.35159, 2.17279)),
    "TiN": ((1.64845, 1.15052, 1.37982), (3.36833, 1.9435, 1.10207)),
    "TiN_palik": ((1.64845, 1.15052, 1.37982), (3.36833, 1.9435, 1.10207)),
    "TiO2": ((3.45661, 2.80174, 2.90517), (0.000105265, 0, 0.000652886)),
    "TiO2-e": ((3.10656, 2.51317, 2.58244), (2.97516e-05, 0, 0.000182698)),
    "TiO2-e_palik": ((3.10656, 2.51317, 2.58244), (2.97516e-05, 0, 0.000182698)),
    "TiO2_palik": ((3.45661, 2.80174, 2.90517), (0.000105265, 0, 0.000652886)),
    "VC": ((3.65757, 2.75274, 2.53267), (3.0683, 2.19869, 1.96319)),
    "VC_palik": ((3.65757, 2.75274, 2.53267), (3.0683, 2.19869, 1.96319)),
    "VN": ((2.8656, 2.11919, 1.94009), (3.03224, 2.05612, 1.61631)),
    "VN_palik": ((2.8656, 2.11919, 1.94009), (3.03224, 2.05612, 1.61631)),
    "V_palik": ((4.27758, 3.51295, 2.76107), (3.4913, 2.88945, 3.11152)),
    "W": ((4.37082, 3.30025, 2.99841), (3.50064, 2.60487, 2.27323)),
    "a-C": ((2.94405, 2.22714, 1.96816), (0.887465, 0.799298, 0.81529)),
    "d-C": ((2.70872, 2.31883, 2.2289), (0, 0, 0)),
    "d-C_palik": ((2.70872, 2.31883, 2.2289), (0, 0, 0)),
}

# ---- Mitsuba's tables (src/core/spectrum.cpp cie1931_tbl, include/mitsuba/core/spectrum.h d65_table)
_CIE_X = (
    0.0001299, 0.0002321, 0.0004149, 0.0007416, 0.001368, 0.002236, 0.004243, 0.00765,
    0.01431, 0.02319, 0.04351, 0.07763, 0.13438, 0.21477, 0.2839, 0.3285,
    0.34828, 0.34806, 0.3362, 0.3187, 0.2908, 0.2511, 0.19536, 0.1421,
    0.09564, 0.05795001, 0.03201, 0.0147, 0.0049, 0.0024, 0.0093, 0.0291,
    0.06327, 0.1096, 0.1655, 0.2257499, 0.2904, 0.3597, 0.4334499, 0.5120501,
    0.5945, 0.6784, 0.7621, 0.8425, 0.9163, 0.9786, 1.0263, 1.0567,
    1.0622, 1.0456, 1.0026, 0.9384, 0.8544499, 0.7514, 0.6424, 0.5419,
    0.4479, 0.3608, 0.2835, 0.2187, 0.1649, 0.1212, 0.0874, 0.0636,
    0.04677, 0.0329, 0.0227, 0.01584, 0.01135916, 0.008110916, 0.005790346, 0.004109457,
    0.002899327, 0.00204919, 0.001439971, 0.000999949, 0.000690079, 0.000476021, 0.000332301, 0.000234826,
    0.000166151, 0.000117413, 0.000083075, 0.000058707, 0.00004151, 0.000029353, 0.000020674, 0.00001456,
    0.000010254, 0.000007221, 0.000005086, 0.000003582, 0.000002523, 0.000001777, 0.000001251,
)
_CIE_Y = (
    0.000003917, 0.000006965, 0.00001239, 0.00002202, 0.000039, 0.000064, 0.00012, 0.000217,
    0.000396, 0.00064, 0.00121, 0.00218, 0.004, 0.0073, 0.0116, 0.01684,
    0.023, 0.0298, 0.038, 0.048, 0.06, 0.0739, 0.09098, 0.1126,
    0.13902, 0.1693, 0.20802, 0.2586, 0.323, 0.4073, 0.503, 0.6082,
    0.71, 0.7932, 0.862, 0.9148501, 0.954, 0.9803, 0.9949501, 1.0,
    0.995, 0.9786, 0.952, 0.9154, 0.87, 0.8163, 0.757, 0.6949,
    0.631, 0.5668, 0.503, 0.4412, 0.381, 0.321, 0.265, 0.217,
    0.175, 0.1382, 0.107, 0.0816, 0.061, 0.04458, 0.032, 0.0232,
    0.017, 0.01192, 0.00821, 0.005723, 0.004102, 0.002929, 0.002091, 0.001484,
    0.001047, 0.00074, 0.00052, 0.0003611, 0.0002492, 0.0001719, 0.00012, 0.0000848,
    0.00006, 0.0000424, 0.00003, 0.0000212, 0.00001499, 0.0000106, 0.000007466, 0.000005258,
    0.000003703, 0.000002608, 0.000001837, 0.000001293, 0.000000911, 0.000000642, 0.000000452,
)
_CIE_Z = (
    0.0006061, 0.001086, 0.001946, 0.003486, 0.006450001, 0.01054999, 0.02005001, 0.03621,
    0.06785001, 0.1102, 0.2074, 0.3713, 0.6456, 1.0390501, 1.3856, 1.62296,
    1.74706, 1.7826, 1.77211, 1.7441, 1.6692, 1.5281, 1.28764, 1.0419,
    0.8129501, 0.6162, 0.46518, 0.3533, 0.272, 0.2123, 0.1582, 0.1117,
    0.07824999, 0.05725001, 0.04216, 0.02984, 0.0203, 0.0134, 0.008749999, 0.005749999,
    0.0039, 0.002749999, 0.0021, 0.0018, 0.001650001, 0.0014, 0.0011, 0.001,
    0.0008, 0.0006, 0.00034, 0.00024, 0.00019, 0.0001, 0.00005, 0.00003,
    0.00002, 0.00001, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0,
    0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0,
    0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0,
    0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0,
    0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0,
)
_D65 = (
    46.6383, 49.3637, 52.0891, 51.0323, 49.9755, 52.3118, 54.6482, 68.7015, 82.7549, 87.1204,
    91.486, 92.4589, 93.4318, 90.057, 86.6823, 95.7736, 104.865, 110.936, 117.008, 117.41,
    117.812, 116.336, 114.861, 115.392, 115.923, 112.367, 108.811, 109.082, 109.354, 108.578,
    107.802, 106.296, 104.79, 106.239, 107.689, 106.047, 104.405, 104.225, 104.046, 102.023,
    100.0, 98.1671, 96.3342, 96.0611, 95.788, 92.2368, 88.6856, 89.3459, 90.0062, 89.8026,
    89.5991, 88.6489, 87.6987, 85.4936, 83.2886, 83.4939, 83.6992, 81.863, 80.0268, 80.1207,
    80.2146, 81.2462, 82.2778, 80.281, 78.2842, 74.0027, 69.7213, 70.6652, 71.6091, 72.979,
    74.349, 67.9765, 61.604, 65.7448, 69.8856, 72.4863, 75.087, 69.3398, 63.5927, 55.0054,
    46.4182, 56.6118, 66.8054, 65.0941, 63.3828, 63.8434, 64.304, 61.8779, 59.4519, 55.7054,
    51.959, 54.6998, 57.4406, 58.8765, 60.3125,
)
