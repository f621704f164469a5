"""The chart of the eleven MTL illumination models in docs/formats.md, made from an OBJ + MTL file.

    python examples/formats/illum_chart.py    # writes docs/images/formats/illum_chart.png (a minute or two)

It writes an OBJ with eleven spheres (smoothing group 1, so their normals come from the importer) on a floor
in front of a striped wall, and an MTL with one material per `illum` 0-10, all from the same Ka Kd Ks Ns Ni Tf
(an orange plastic with a white highlight, a 70 % transmission filter, index 1.5). It imports the pair with
`lumos.io.obj.import_obj`, renders each sphere with `whitted` from the same relative view, and captions the
panels with the model and the lumos coefficients the importer chose.
"""

from __future__ import annotations

import sys
import tempfile
from pathlib import Path

import numpy as np

import lumos
from lumos.io.obj import import_obj

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # examples/: the figure scripts' shared kit
from figure_kit import compose, png8, save_image  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
OUT = ROOT / "docs" / "images" / "formats" / "illum_chart.png"
SPACING, RADIUS, SIZE = 3.0, 1.0, 200
NAMES = ["colour only", "ambient + diffuse", "+ highlight", "+ ray-traced reflection", "glass",
         "Fresnel mirror", "refraction", "Fresnel refraction", "reflection, no ray tracing",
         "glass, no ray tracing", "shadow matte"]
MATERIAL = "Ka 0.1 0.04 0.01\nKd 0.8 0.3 0.08\nKs 0.25 0.25 0.25\nNs 80\nNi 1.5\nTf 0.7 0.7 0.7\n"


def sphere_obj(center, first: int, rings: int = 24, segments: int = 48) -> tuple[list[str], int]:
    """An OBJ UV sphere (quads, triangles at the poles) whose first vertex is number `first`."""
    lines = []
    for i in range(rings + 1):
        theta = np.pi * i / rings
        for j in range(segments):
            phi = 2 * np.pi * j / segments
            p = center + RADIUS * np.array([np.sin(theta) * np.sin(phi), np.cos(theta), np.sin(theta) * np.cos(phi)])
            lines.append(f"v {p[0]:.6f} {p[1]:.6f} {p[2]:.6f}")
    for i in range(rings):
        for j in range(segments):
            a, b = first + i * segments + j, first + i * segments + (j + 1) % segments
            c, d = a + segments, b + segments
            if i == 0:
                lines.append(f"f {a} {c} {d}")
            elif i == rings - 1:
                lines.append(f"f {a} {c} {b}")
            else:
                lines.append(f"f {a} {c} {d} {b}")
    return lines, first + (rings + 1) * segments


def write_files(folder: Path) -> Path:
    """chart.obj + chart.mtl in `folder`; returns the OBJ's path."""
    mtl = [f"newmtl illum{k}\n{MATERIAL}illum {k}\n" for k in range(11)]
    mtl += ["newmtl floor\nKa 0.5 0.5 0.5\nKd 0.55 0.55 0.5\nillum 1\n",
            "newmtl stripe_dark\nKa 0.1 0.15 0.3\nKd 0.1 0.15 0.3\nillum 1\n",
            "newmtl stripe_light\nKa 0.9 0.9 0.85\nKd 0.9 0.9 0.85\nillum 1\n"]
    (folder / "chart.mtl").write_text("\n".join(mtl))
    lines, next_v = ["mtllib chart.mtl"], 1
    width = 11 * SPACING
    x0, x1 = -SPACING, width
    lines += [f"v {x0} 0 -4", f"v {x1} 0 -4", f"v {x1} 0 4", f"v {x0} 0 4", "o floor", "usemtl floor", "s off",
              "f 4 3 2 1"]
    next_v += 4
    stripe = 0.75
    for k, x in enumerate(np.arange(x0, x1, stripe)):
        lines += [f"v {x} 0 -3", f"v {x + stripe} 0 -3", f"v {x + stripe} 5 -3", f"v {x} 5 -3",
                  "o wall", f"usemtl stripe_{'dark' if k % 2 else 'light'}", f"f {next_v} {next_v + 1} "
                  f"{next_v + 2} {next_v + 3}"]
        next_v += 4
    for k in range(11):
        sphere, next_v = sphere_obj(np.array([k * SPACING, RADIUS, 0.0]), next_v)
        lines += [f"o sphere{k}", f"usemtl illum{k}", "s 1"] + sphere
    path = folder / "chart.obj"
    path.write_text("\n".join(lines) + "\n")
    return path


def caption(k: int, m: dict) -> str:
    """Three lines: the model, its local terms, its ray-traced terms."""
    def terms(keys):
        return [f"{key} {np.mean(m[key]):.2f}" for key in keys if max(m[key]) > 0]
    local = terms(("kd", "ks", "emission")) or ["black"]
    rays = terms(("kr", "kt")) + ([f"ior {m['ior']:.3g}"] if max(m["kt"]) > 0 else [])
    rays += ["fresnel"] if m["fresnel"] else []
    return f"illum {k}: {NAMES[k]}\n{'  '.join(local)}\n{'  '.join(rays)}"


def main() -> None:
    with tempfile.TemporaryDirectory() as folder:
        model = import_obj(write_files(Path(folder)))
    for warning in model.warnings:
        print("  import:", warning)
    panels = []
    for k in range(11):
        x = k * SPACING
        scene = lumos.load_scene({
            "camera": {"position": [x + 0.8, 2.2, 4.6], "look_at": [x, 0.9, 0], "fov": 34},
            "render": {"method": "whitted", "width": SIZE, "height": SIZE, "spp": 4, "max_depth": 6},
            "ambient": 0.15, "background": [0.55, 0.7, 0.9],
            "lights": [{"type": "point", "position": [x + 4, 7, 6], "intensity": 0.9}],
            "materials": model.materials, "objects": model.objects})
        image = lumos.render(scene)
        panels.append((caption(k, model.materials[f"illum{k}"]), png8(image.array)))
        print(f"illum {k} rendered", flush=True)
    OUT.parent.mkdir(parents=True, exist_ok=True)
    save_image(compose(panels, columns=4), OUT, ROOT)


if __name__ == "__main__":
    main()
