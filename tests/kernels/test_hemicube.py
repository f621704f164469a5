"""Hemicube form factors (`kernels.hemicube`) against closed forms, the contour integral and conservation.

* the ΔF table: its raw (midpoint) sum converges to 1 at second order (1 + 1.3e-4 at res 64); normalised, as
  the kernels use it, it sums to 1 to 1e-12; each entry is the exact form factor of its pixel's square (the
  contour integral) to O(1/res²) (0.26% at worst at res 32);
* closed scenes: from any point inside a closed box or a tessellated sphere, every pixel sees a patch (total 1);
* point to polygon: Lambert's contour formula (`contour_ff`, the reference twin) for polygons above the point,
  crossing its base plane, spanning several faces and partly behind it, in random orientations;
* area to area: Howell's catalogue (parallel rectangles, perpendicular squares, coaxial disks), the hemicube's
  point-to-area values averaged over 8×8 Gauss–Legendre points of the receiver (64 hemicubes; the quadrature
  alone is exact to 4e-7 here, so what is left is the hemicube's error);
* occlusion: a blocker between two squares leaves what the contour formula of the visible part gives;
* random rotations about the normal average the aliasing of a small patch out;
* the parallel matrix kernel equals the single-point entry row by row.

`python tests/kernels/test_hemicube.py` prints hemicubes per second (res 64 and 128, 1,000 and 10,000 quads).
"""

import math

import numpy as np
import pytest

from lumos.kernels import hemicube as H

OFFSET = 1e-6  # how far the tests lift a point off its surface along its normal
NEAR = 1e-9  # the hemicube's near plane: far below OFFSET


# ----------------------------------------------------------------------------- references (NumPy)


def contour_ff(x, n, polygon):
    """Lambert's contour formula: the form factor from the differential area at x with unit normal n to a
    polygon (float (k, 3) corners) wholly on or above x's tangent plane, unoccluded:
    F = (1/2π) Σ acos(dᵢ·dᵢ₊₁) n·unit(dᵢ × dᵢ₊₁), dᵢ the unit directions from x to the corners (the sign follows
    the winding; its magnitude is returned)."""
    d = np.asarray(polygon, float) - x
    d /= np.linalg.norm(d, axis=1)[:, None]
    d_next = np.roll(d, -1, axis=0)
    c = np.cross(d, d_next)
    c /= np.linalg.norm(c, axis=1)[:, None]
    angle = np.arccos(np.clip(np.sum(d * d_next, axis=1), -1.0, 1.0))
    return abs(np.sum(angle * (c @ n))) / (2.0 * math.pi)


def clip_above(x, n, polygon):
    """The part of a convex polygon on the side of x's tangent plane that n points to (Sutherland–Hodgman)."""
    P = np.asarray(polygon, float)
    s = (P - x) @ n
    out = []
    for k in range(len(P)):
        j = (k + 1) % len(P)
        if s[k] >= 0:
            out.append(P[k])
        if (s[k] >= 0) != (s[j] >= 0):
            out.append(P[k] + s[k] / (s[k] - s[j]) * (P[j] - P[k]))
    return np.array(out)


def howell_parallel(a, b, c):
    """Howell C-11: directly opposed parallel rectangles a × b at distance c."""
    X, Y = a / c, b / c
    return 2.0 / (math.pi * X * Y) * (
        math.log(math.sqrt((1 + X * X) * (1 + Y * Y) / (1 + X * X + Y * Y)))
        + X * math.sqrt(1 + Y * Y) * math.atan(X / math.sqrt(1 + Y * Y))
        + Y * math.sqrt(1 + X * X) * math.atan(Y / math.sqrt(1 + X * X))
        - X * math.atan(X) - Y * math.atan(Y))


def howell_perpendicular(h, w, l=1.0):
    """Howell C-14: from rectangle 1 (h × l) to rectangle 2 (w × l), perpendicular, sharing the edge of length l."""
    H_, W = h / l, w / l
    A = (1 + W * W) * (1 + H_ * H_) / (1 + W * W + H_ * H_)
    B = (W * W * (1 + W * W + H_ * H_) / ((1 + W * W) * (W * W + H_ * H_))) ** (W * W)
    C = (H_ * H_ * (1 + H_ * H_ + W * W) / ((1 + H_ * H_) * (H_ * H_ + W * W))) ** (H_ * H_)
    r = math.sqrt(H_ * H_ + W * W)
    return (W * math.atan(1 / W) + H_ * math.atan(1 / H_) - r * math.atan(1 / r) + 0.25 * math.log(A * B * C)) / (
        math.pi * W)


def coaxial_disks(r1, r2, h):
    """Disk of radius r1 to a coaxial parallel disk of radius r2 at distance h."""
    R1, R2 = r1 / h, r2 / h
    X = 1 + (1 + R2 * R2) / (R1 * R1)
    return 0.5 * (X - math.sqrt(X * X - 4 * (R2 / R1) ** 2))


# ----------------------------------------------------------------------------- geometry


class Geometry:
    """Polygons as the hemicube takes them: verts (nv, 3), polys int32 (np, 4), poly_normal (np, 3),
    side_patch int32 (np, 2)."""

    def __init__(self):
        self.verts, self.polys, self.normals, self.sides = [], [], [], []

    def polygon(self, corners, front=-1, back=-1):
        """A triangle or planar convex quad; its normal is the one its corners turn counter-clockwise about."""
        corners = np.asarray(corners, float)
        nrm = np.cross(corners[1] - corners[0], corners[2] - corners[0])
        base = len(self.verts)
        self.verts.extend(corners)
        idx = list(range(base, base + len(corners))) + [-1] * (4 - len(corners))
        self.polys.append(idx)
        self.normals.append(nrm / np.linalg.norm(nrm))
        self.sides.append((front, back))
        return len(self.polys) - 1

    def rect(self, corner, e1, e2, nu=1, nv=1, front=-1, back=-1):
        """A rectangle corner + [0, 1]·e1 + [0, 1]·e2 (normal e1 × e2) as nu × nv quads."""
        corner, e1, e2 = (np.asarray(a, float) for a in (corner, e1, e2))
        for i in range(nu):
            for j in range(nv):
                p = corner + e1 * i / nu + e2 * j / nv
                self.polygon([p, p + e1 / nu, p + e1 / nu + e2 / nv, p + e2 / nv], front, back)

    def disk(self, centre, normal, radius, segments, front=-1, back=-1):
        """A disk as a fan of triangles (normal `normal`)."""
        centre, normal = np.asarray(centre, float), np.asarray(normal, float)
        u, v = basis(normal)
        a = 2 * math.pi * np.arange(segments + 1) / segments
        ring = centre + radius * (np.cos(a)[:, None] * u + np.sin(a)[:, None] * v)
        for k in range(segments):
            self.polygon([centre, ring[k], ring[k + 1]], front, back)

    def arrays(self):
        return (np.array(self.verts, float), np.array(self.polys, np.int32), np.array(self.normals, float),
                np.array(self.sides, np.int32))


def basis(n):
    n = np.asarray(n, float)
    a = np.array([1.0, 0, 0]) if abs(n[0]) < 0.9 else np.array([0, 1.0, 0])
    u = np.cross(n, a)
    u /= np.linalg.norm(u)
    return u, np.cross(n, u)


def random_unit(rng):
    v = rng.normal(size=3)
    return v / np.linalg.norm(v)


def point_ff(geo, x, n, res, phi=0.0, skip=-1, n_patches=None):
    """float64 (n_patches,): the hemicube form factors from x (lifted OFFSET along n) to every patch."""
    verts, polys, normals, sides = geo.arrays()
    n = np.asarray(n, float) / np.linalg.norm(n)
    x = np.asarray(x, float) + OFFSET * n
    n_patches = n_patches or int(sides.max()) + 1
    return H.form_factors_from_point(x, n, float(phi), np.int64(skip), verts, polys, normals, sides,
                                     H.delta_form_factors(res), NEAR, np.int64(n_patches))


def matrix_ff(geo, points, normal, res, skips, phis=None):
    """float32 (n_points, n_patches) through the parallel kernel."""
    verts, polys, normals, sides = geo.arrays()
    points = np.ascontiguousarray(points, float)
    nrm = np.broadcast_to(np.asarray(normal, float), points.shape).copy()
    phis = np.zeros(len(points)) if phis is None else np.asarray(phis, float)
    out = np.zeros((len(points), int(sides.max()) + 1), np.float32)
    H.form_factor_matrix(points + OFFSET * nrm, nrm, phis, np.asarray(skips, np.int32), verts, polys, normals,
                         sides, H.delta_form_factors(res), NEAR, out)
    return out


def gauss_grid(corner, e1, e2, order=8):
    """Gauss–Legendre points (order²) on the rectangle corner + [0,1]·e1 + [0,1]·e2 and weights summing to 1."""
    t, w = np.polynomial.legendre.leggauss(order)
    t, w = (t + 1) / 2, w / 2
    corner, e1, e2 = (np.asarray(a, float) for a in (corner, e1, e2))
    pts = np.array([corner + a * e1 + b * e2 for a in t for b in t])
    return pts, np.outer(w, w).ravel()


# ----------------------------------------------------------------------------- the ΔF table


def test_delta_form_factors_sum_to_one_at_second_order():
    raw = {res: H.delta_form_factors(res, False).sum() for res in (16, 32, 64, 128)}
    # the midpoint rule of an integral whose value is 1: its error falls 4× when res doubles
    for res in (16, 32, 64):
        assert (raw[res] - 1) / (raw[2 * res] - 1) == pytest.approx(4.0, rel=0.02)
    assert abs(raw[64] - 1) < 2e-4
    for res in (2, 16, 64, 128):
        table = H.delta_form_factors(res)
        assert table.shape == (3 * res, res)
        assert abs(table.sum() - 1) < 1e-12
    with pytest.raises(ValueError):
        H.delta_form_factors(15)


def worst_pixel_error(res):
    """Largest relative difference between the ΔF table and the exact form factor of each pixel's square
    (the contour integral), over the top face and one side face."""
    table = H.delta_form_factors(res, False)
    x, n = np.zeros(3), np.array([0.0, 0, 1])
    edges = np.linspace(-1, 1, res + 1)
    worst = 0.0
    for r in range(res):  # top face: row 0 at y = +1
        for c in range(res):
            sq = [[edges[c], -edges[r], 1], [edges[c + 1], -edges[r], 1], [edges[c + 1], -edges[r + 1], 1],
                  [edges[c], -edges[r + 1], 1]]
            worst = max(worst, abs(table[r, c] / contour_ff(x, n, sq) - 1))
    for r in range(res // 2):  # a side face (x = 1): row 0 at the top, z = 1
        for c in range(res):
            sq = [[1, edges[c], 1 - 2 * r / res], [1, edges[c + 1], 1 - 2 * r / res],
                  [1, edges[c + 1], 1 - 2 * (r + 1) / res], [1, edges[c], 1 - 2 * (r + 1) / res]]
            worst = max(worst, abs(table[res + r, c] / contour_ff(x, n, sq) - 1))
    return worst


def test_each_delta_form_factor_is_the_form_factor_of_its_pixel():
    coarse, fine = worst_pixel_error(16), worst_pixel_error(32)
    assert fine < 0.003  # the midpoint rule per pixel: O(1/res²)
    assert coarse / fine == pytest.approx(4.0, rel=0.1)


# ----------------------------------------------------------------------------- closed scenes


def closed_box(nu=3, size=1.0):
    """The cube [0, size]³ as nu × nu quads per face, normals inward; each quad its own patch (front side).
    Faces in the order z = 0, z = size, x = 0, x = size, y = 0, y = size (patches nu² apart)."""
    g = Geometry()
    s = float(size)
    centre = np.full(3, s / 2)
    patch = 0
    for axis in (2, 0, 1):
        for level in (0.0, s):
            a, b = [i for i in range(3) if i != axis]
            for i in range(nu):
                for j in range(nu):
                    quad = np.zeros((4, 3))
                    quad[:, axis] = level
                    for k, (du, dv) in enumerate([(0, 0), (1, 0), (1, 1), (0, 1)]):
                        quad[k, a] = s * (i + du) / nu
                        quad[k, b] = s * (j + dv) / nu
                    if np.cross(quad[1] - quad[0], quad[2] - quad[0]) @ (centre - quad[0]) < 0:
                        quad = quad[::-1]
                    g.polygon(quad, front=patch)
                    patch += 1
    return g


@pytest.mark.parametrize("res", [16, 64])
def test_from_the_centre_of_a_closed_box_every_pixel_sees_a_patch(res):
    g = closed_box()
    ff = point_ff(g, [0.5, 0.5, 0.5 - OFFSET], [0, 0, 1], res)
    assert abs(ff.sum() - 1) < 1e-12
    # the ceiling (patches 9..17) from the centre: a 2 × 2 square one unit away, seen from its centre
    ceiling = contour_ff(np.zeros(3), np.array([0, 0, 1.0]), [[-1, -1, 1], [1, -1, 1], [1, 1, 1], [-1, 1, 1]])
    assert ff[9:18].sum() == pytest.approx(ceiling, rel=2e-3 if res == 64 else 2e-2)


def test_anywhere_in_a_closed_box_at_any_rotation_every_pixel_sees_a_patch(rng):
    g = closed_box(nu=4, size=2.0)
    for _ in range(12):
        x = rng.uniform(0.2, 1.8, 3)
        ff = point_ff(g, x, random_unit(rng), 32, phi=rng.uniform(0, 2 * math.pi))
        assert abs(ff.sum() - 1) < 1e-12


def test_inside_a_tessellated_sphere_every_pixel_sees_a_patch(rng):
    trimesh = pytest.importorskip("trimesh")
    sphere = trimesh.creation.icosphere(subdivisions=3, radius=1.0)  # 1,280 triangles, normals outward
    g = Geometry()
    for k, f in enumerate(sphere.faces):
        g.polygon(sphere.vertices[f], front=-1, back=k)  # the inside is the back side
    centre = point_ff(g, [0.0, 0.0, 0.0], [0, 0, 1], 64)
    assert abs(centre.sum() - 1) < 1e-12
    for _ in range(6):
        x = rng.uniform(-0.5, 0.5, 3)
        ff = point_ff(g, x, random_unit(rng), 64, phi=rng.uniform(0, 2 * math.pi))
        assert abs(ff.sum() - 1) < 1e-12


# ----------------------------------------------------------------------------- point to polygon


def polygon_cases():
    """(name, corners in the frame (t1, t2, n) of the point at the origin): above, crossing the base plane,
    spanning several faces, partly behind the point."""
    return [
        ("triangle overhead", [[-0.3, -0.2, 1.0], [0.6, -0.1, 1.2], [0.1, 0.7, 0.9]]),
        ("slanted quad off-axis", [[0.5, 0.2, 0.4], [1.5, 0.3, 0.9], [1.4, 1.1, 1.3], [0.4, 1.0, 0.8]]),
        ("wall crossing the base plane", [[1.0, -1.0, -0.5], [1.0, 1.0, -0.5], [1.0, 1.0, 1.0], [1.0, -1.0, 1.0]]),
        ("big ceiling over all five faces", [[-3.0, -3.0, 0.5], [3.0, -3.0, 0.5], [3.0, 3.0, 0.5], [-3.0, 3.0, 0.5]]),
        ("tilted quad partly behind", [[-2.0, -0.5, 0.2], [0.5, -0.5, 1.5], [0.5, 0.8, 1.5], [-2.0, 0.8, 0.2]]),
        ("sliver through the base plane behind", [[-1.5, -0.4, -0.6], [-0.5, 0.6, 0.8], [-1.2, 0.9, 0.5]]),
    ]


@pytest.mark.parametrize("case", range(len(polygon_cases())))
def test_point_to_polygon_matches_the_contour_formula(rng, case):
    name, local = polygon_cases()[case]
    local = np.array(local, float)
    for _ in range(3):  # random orientations of the whole configuration
        n = random_unit(rng)
        u, v = basis(n)
        x = rng.uniform(-1, 1, 3)
        world = x + local[:, :1] * u + local[:, 1:2] * v + local[:, 2:] * n
        g = Geometry()
        g.polygon(world, front=0, back=0)
        ff = point_ff(g, x, n, 128, phi=rng.uniform(0, 2 * math.pi))
        exact = contour_ff(x, n, clip_above(x, n, world))
        assert ff[0] == pytest.approx(exact, rel=0.01, abs=2e-4), name


def test_polygons_below_the_base_plane_or_skipped_add_nothing():
    g = Geometry()
    g.polygon([[-1, -1, -0.1], [1, -1, -0.1], [1, 1, -0.5], [-1, 1, -0.5]], front=0, back=0)  # below
    g.polygon([[-1, -1, 0.0], [1, -1, 0.0], [1, 1, 0.0], [-1, 1, 0.0]], front=1, back=1)  # x's own polygon
    g.polygon([[-1, -1, 1.0], [1, -1, 1.0], [1, 1, 1.0]], front=2, back=2)
    ff = point_ff(g, [0.2, 0.1, 0.0], [0, 0, 1], 32, skip=1)
    assert ff[0] == 0.0 and ff[1] == 0.0 and ff[2] > 0.1
    assert point_ff(g, [0.2, 0.1, 0.0], [0, 0, 1], 32, skip=2)[2] == 0.0  # skip_poly is never drawn


def test_the_side_seen_decides_the_patch():
    g = Geometry()
    g.polygon([[-1, -1, 1.0], [1, -1, 1.0], [1, 1, 1.0], [-1, 1, 1.0]], front=3, back=5)  # normal +z
    g.polygon([[-1, -1, 3.0], [-1, 1, 3.0], [1, 1, 3.0], [1, -1, 3.0]], front=-1, back=4)  # normal −z
    below = point_ff(g, [0, 0, 0.0], [0, 0, 1], 32, n_patches=6)  # on the back side of polygon 0
    between = point_ff(g, [0, 0, 2.0], [0, 0, 1], 32, n_patches=6)  # front of 0, but facing polygon 1's front
    assert below[5] > 0.5 and below[3] == 0 and below[4] == 0  # polygon 0 hides polygon 1
    assert between.sum() == 0  # sees only polygon 1's front, which is no patch (−1): it adds nothing
    above = point_ff(g, [0, 0, 2.0], [0, 0, -1], 32, n_patches=6)  # looking down at polygon 0's front
    assert above[3] > 0.5 and above[5] == 0


# ----------------------------------------------------------------------------- area to area (Howell)


def area_ff(geo, grid, normal, res, skips, phis=None):
    pts, w = grid
    return float(matrix_ff(geo, pts, normal, res, skips, phis)[:, 1] @ w)


@pytest.mark.parametrize("res", [64, 128])
def test_parallel_unit_squares(res):
    g = Geometry()
    g.rect([0, 0, 0], [1, 0, 0], [0, 1, 0], front=0)
    g.rect([0, 0, 1], [0, 1, 0], [1, 0, 0], front=1)  # facing down
    exact = howell_parallel(1, 1, 1)
    assert exact == pytest.approx(0.19982, abs=1e-5)
    F = area_ff(g, gauss_grid([0, 0, 0], [1, 0, 0], [0, 1, 0]), [0, 0, 1], res, np.zeros(64))
    assert F == pytest.approx(exact, rel=0.01)


@pytest.mark.parametrize("res", [64, 128])
def test_opposed_parallel_rectangles(res):
    g = Geometry()
    g.rect([0, 0, 0], [1, 0, 0], [0, 1.5, 0], front=0)
    g.rect([0, 0, 0.5], [0, 1.5, 0], [1, 0, 0], front=1)
    exact = howell_parallel(1, 1.5, 0.5)  # X = 2, Y = 3: 0.475576
    assert exact == pytest.approx(0.4756, abs=1e-4)
    F = area_ff(g, gauss_grid([0, 0, 0], [1, 0, 0], [0, 1.5, 0]), [0, 0, 1], res, np.zeros(64))
    assert F == pytest.approx(exact, rel=0.01)


@pytest.mark.parametrize("res", [64, 128])
def test_perpendicular_squares_sharing_an_edge(res):
    g = Geometry()
    g.rect([0, 0, 0], [1, 0, 0], [0, 1, 0], front=0)  # z = 0, normal +z
    g.rect([0, 0, 0], [0, 1, 0], [0, 0, 1], front=1)  # x = 0, normal +x
    exact = howell_perpendicular(1, 1)
    assert exact == pytest.approx(0.20004, abs=1e-5)
    F = area_ff(g, gauss_grid([0, 0, 0], [1, 0, 0], [0, 1, 0]), [0, 0, 1], res, np.zeros(64))
    assert F == pytest.approx(exact, rel=0.01)


def test_coaxial_disks():
    g = Geometry()
    g.disk([0, 0, 0], [0, 0, 1], 1.0, 256, front=0)
    g.disk([0, 0, 3], [0, 0, -1], 1.0, 256, front=1)
    exact = coaxial_disks(1, 1, 3)
    assert exact == pytest.approx((11 - math.sqrt(117)) / 2, rel=1e-12)
    # receiver points: Gauss–Legendre in r (weight r dr) × 8 angles, on the tessellated disk z = 0
    t, w = np.polynomial.legendre.leggauss(8)
    r, w = (t + 1) / 2, w / 2 * (t + 1)  # ∫₀¹ f r dr · 2 (the disk's area π normalises the angle sum)
    ang = 2 * math.pi * (np.arange(8) + 0.5) / 8
    pts = np.array([[ri * math.cos(a), ri * math.sin(a), 0.0] for ri in r for a in ang])
    weights = np.repeat(w, 8) / 8
    skips = np.full(len(pts), -1)  # x sits 1e-6 above its own disk: the disk lies below its base plane
    F = float(matrix_ff(g, pts, [0, 0, 1], 128, skips)[:, 1] @ weights)
    assert F == pytest.approx(exact, rel=0.01)


# ----------------------------------------------------------------------------- occlusion


def test_a_blocker_hides_what_the_contour_formula_of_the_visible_part_says():
    # squares z = 0 and z = 1; a blocker at z = 0.5 over x >= 0.6: from (x0, y, 0) it hides z = 1 beyond
    # x = x0 + 2(0.6 − x0) = 1.2 − x0, so the visible part of the top square is [0, min(1, 1.2 − x0)] × [0, 1]
    def scene(blocked):
        g = Geometry()
        g.rect([0, 0, 0], [1, 0, 0], [0, 1, 0], front=0)
        g.rect([0, 0, 1], [0, 1, 0], [1, 0, 0], front=1)
        if blocked:
            g.rect([0.6, -2, 0.5], [0, 4, 0], [3, 0, 0], front=2, back=-1)  # its underside a patch
        return g

    up = np.array([0, 0, 1.0])
    pts, w = gauss_grid([0, 0, 0], [1, 0, 0], [0, 1, 0])
    visible = []
    for p in pts:
        edge = min(1.0, 1.2 - p[0])
        visible.append(contour_ff(p, up, [[0, 0, 1], [edge, 0, 1], [edge, 1, 1], [0, 1, 1]]) if edge > 0 else 0.0)
    exact_blocked = float(np.array(visible) @ w)
    exact_open = howell_parallel(1, 1, 1)
    F_open = area_ff(scene(False), (pts, w), up, 128, np.zeros(64))
    F_blocked = area_ff(scene(True), (pts, w), up, 128, np.zeros(64))
    assert exact_blocked < 0.8 * exact_open  # the blocker matters
    assert F_blocked == pytest.approx(exact_blocked, rel=0.01)
    assert F_open - F_blocked == pytest.approx(exact_open - exact_blocked, rel=0.03)
    # one point: the blocker's underside gets what it hides of the hemisphere (its own contour, clipped to
    # the half-plane it covers) and the square what is left
    x = np.array([0.3, 0.4, 0.0])
    ff = point_ff(scene(True), x, up, 128, n_patches=3)
    blocker = contour_ff(x, up, [[0.6, -2, 0.5], [3.6, -2, 0.5], [3.6, 2, 0.5], [0.6, 2, 0.5]])
    assert ff[2] == pytest.approx(blocker, rel=0.01)
    assert ff[1] == pytest.approx(contour_ff(x, up, [[0, 0, 1], [0.9, 0, 1], [0.9, 1, 1], [0, 1, 1]]), rel=0.01)


# ----------------------------------------------------------------------------- rotations


def test_random_rotations_average_the_aliasing_out():
    # a small square (1.6 × 1.6 pixels of a res-32 top face) seen off-axis: one hemicube aliases badly
    g = Geometry()
    sq = np.array([[0.7, 0.45, 1.0], [0.8, 0.45, 1.0], [0.8, 0.55, 1.0], [0.7, 0.55, 1.0]])
    g.polygon(sq, front=0, back=0)
    x, n = np.zeros(3), np.array([0, 0, 1.0])
    exact = contour_ff(x, n, sq)
    rng = np.random.default_rng(7)
    shots = np.array([point_ff(g, x, n, 32, phi=p)[0] for p in rng.uniform(0, 2 * math.pi, 400)])
    fixed_error = np.median(np.abs(shots - exact))  # what one fixed rotation gets wrong, typically
    assert fixed_error > 0.1 * exact
    assert abs(point_ff(g, x, n, 32, phi=0.0)[0] - exact) > 0.1 * exact
    mean_error = abs(shots.mean() - exact)
    assert mean_error < 0.01 * exact
    assert mean_error < fixed_error / 10


# ----------------------------------------------------------------------------- the kernels agree


def test_matrix_rows_equal_single_point_shots(rng):
    g = closed_box(nu=2)
    verts, polys, normals, sides = g.arrays()
    pts = rng.uniform(0.1, 0.9, (11, 3))
    nrm = np.array([random_unit(rng) for _ in range(11)])
    phis = rng.uniform(0, 2 * math.pi, 11)
    skips = np.full(11, -1, np.int32)
    dF = H.delta_form_factors(32)
    out = np.zeros((11, 24), np.float32)
    H.form_factor_matrix(pts, nrm, phis, skips, verts, polys, normals, sides, dF, NEAR, out)
    for i in range(11):
        row = H.form_factors_from_point(pts[i], nrm[i], phis[i], np.int64(-1), verts, polys, normals, sides, dF,
                                        NEAR, np.int64(24))
        assert np.array_equal(out[i], row.astype(np.float32))


# ----------------------------------------------------------------------------- speed (not a test)


def cornell_quads(per_side):
    """A closed, subdivided Cornell-like box: six walls of per_side² quads each, facing in, and two blocks
    standing on the floor (five faces each of (per_side // 3)² quads, facing out); every quad a patch."""
    g = Geometry()

    def face(corner, e1, e2, k, outward_from):
        corner, e1, e2 = (np.asarray(a, float) for a in (corner, e1, e2))
        if np.cross(e1, e2) @ (corner + (e1 + e2) / 2 - outward_from) < 0:
            e1, e2 = e2, e1
        g.rect(corner, e1, e2, k, k)

    box_centre = np.full(3, 0.5)
    for axis in range(3):
        e1, e2 = np.eye(3)[(axis + 1) % 3], np.eye(3)[(axis + 2) % 3]
        for level in (0.0, 1.0):
            face(np.eye(3)[axis] * level, e1, e2, per_side, box_centre + (2 * level - 1) * np.eye(3)[axis])
    for lo, hi in [([0.15, 0, 0.55], [0.45, 0.6, 0.85]), ([0.55, 0, 0.15], [0.85, 0.3, 0.45])]:
        lo, hi = np.array(lo), np.array(hi)
        d = np.diag(hi - lo)
        centre = (lo + hi) / 2
        for axis in range(3):
            e1, e2 = d[(axis + 1) % 3], d[(axis + 2) % 3]
            for corner in (lo, lo + d[axis]):
                if axis == 1 and corner[1] == 0.0:
                    continue  # the bottom stands on the floor
                face(corner, e1, e2, max(1, per_side // 3), centre)
    g.sides = [(i, -1) for i in range(len(g.polys))]
    return g


RES = (64, 128)


def main():
    import time

    import numba

    for per_side in (12, 38):
        g = cornell_quads(per_side)
        verts, polys, normals, sides = g.arrays()
        n_patches = len(polys)
        centres = verts[polys].mean(axis=1)
        rng = np.random.default_rng(1)
        pick = rng.choice(len(polys), 256, replace=False)
        pts = centres[pick] + 1e-6 * normals[pick]
        for res in RES:
            dF = H.delta_form_factors(res)
            out = np.zeros((len(pick), n_patches), np.float32)
            args = (pts, normals[pick], rng.uniform(0, 6.28, len(pick)), pick.astype(np.int32), verts, polys,
                    normals, sides, dF, NEAR, out)
            for threads in (1, numba.config.NUMBA_NUM_THREADS):
                numba.set_num_threads(threads)
                t0 = time.perf_counter()
                H.form_factor_matrix(*args)
                t0 = time.perf_counter()
                H.form_factor_matrix(*args)
                dt = time.perf_counter() - t0
                print(f"{n_patches:6d} quads  res {res:3d}  {threads} thread(s): {len(pick) / dt:8.1f} hemicubes/s"
                      f"  (median row sum {np.median(out.sum(1)):.6f})")


if __name__ == "__main__":
    main()
