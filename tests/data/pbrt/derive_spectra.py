"""Regenerate the named-spectra tables of src/lumos/io/pbrt_spectra.py from pbrt-v4's tabulated data.

    python tests/data/pbrt/derive_spectra.py path/to/pbrt-v4/src/pbrt/util/spectrum.cpp

Prints NAMED_METALS (head-on reflectance F0 of each "metal-X-eta"/"metal-X-k" pair, as a reflectance under D65),
NAMED_GLASSES (η at 550 nm) and NAMED_ILLUMINANTS (colour at luminance 1), computed with pbrt_spectra's own
CIE 1931 functions, to paste into the module. Not run by the tests (pbrt's source is not part of lumos).
"""

import re
import sys

import numpy as np

from lumos.io import pbrt_spectra as ps

METALS = ("Ag", "Al", "Au", "Cu", "CuZn", "MgO", "TiO2")
GLASSES = {"glass-BK7": "GlassBK7", "glass-BAF10": "GlassBAF10", "glass-FK51A": "GlassFK51A",
           "glass-LASF9": "GlassLASF9", "glass-F5": "GlassSF5", "glass-F10": "GlassSF10", "glass-F11": "GlassSF11"}
ILLUMINANTS = {"stdillum-A": "CIE_Illum_A", "stdillum-D50": "CIE_Illum_D5000", "stdillum-D65": "CIE_Illum_D6500",
               **{f"stdillum-F{i}": f"CIE_Illum_F{i}" for i in range(1, 13)}, "illum-acesD60": "ACES_Illum_D60"}


def interleaved(src: str, name: str):
    m = re.search(r"const Float %s\[[^\]]*\]\s*=\s*\{(.*?)\};" % re.escape(name), src, re.S)
    body = re.sub(r"//[^\n]*", "", m.group(1))
    values = np.array([float(x) for x in body.split(",") if x.strip()])
    return values[0::2], values[1::2]


def main(path: str) -> None:
    src = open(path).read()
    print("NAMED_METALS = {")
    for metal in METALS:
        lam, eta = interleaved(src, f"{metal}_eta")
        lam_k, k = interleaved(src, f"{metal}_k")
        fine = np.arange(380.0, 780.5, 1.0)
        f0 = ps.fresnel_f0(np.interp(fine, lam, eta), np.interp(fine, lam_k, k))
        rgb = ps.reflectance_rgb(fine, f0)
        print(f'    "{metal}": ({", ".join(f"{min(c, 1.0):.4f}".rstrip("0").rstrip(".") for c in rgb)}),')
    print("}\nNAMED_GLASSES = {")
    for name, array in GLASSES.items():
        lam, eta = interleaved(src, f"{array}_eta")
        print(f'    "{name}": {float(np.interp(550.0, lam, eta)):.4f},')
    print("}\nNAMED_ILLUMINANTS = {")
    for name, array in ILLUMINANTS.items():
        lam, value = interleaved(src, array)
        rgb = ps.illuminant_rgb(lam, value)
        print(f'    "{name}": ({", ".join(f"{c:.4f}" for c in rgb)}),')
    print("}")


if __name__ == "__main__":
    main(sys.argv[1])
