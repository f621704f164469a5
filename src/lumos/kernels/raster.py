"""Scan-line polygon rasterization with a z-buffer: the kernels of `methods.raster`.

The pipeline, each stage one parallel loop over flat arrays:

1. `project_vertices` — world → camera → clip space with DESIGN.md's camera (so raster and ray-cast images line
   up pixel for pixel): clip (X, Y, W, D) with W the perspective divisor and D the depth in front of the eye,
   and, for vertices in front of the near plane, screen (x, y) in pixels plus the depth key.
2. `bin_prims` — each polygon clipped against the near plane (only the ones that cross it are clipped), culled
   if it faces away (optional), and given the range of pixel rows whose sample points it may cover; prims are
   then sorted into bands of `BAND` rows (`fill_bins`), in their original order within a band.
3. `raster_bands` — one band per task: for every polygon of the band, the classic scan-line algorithm
   (`setup_edges`, `first_covered_row`, `fill_polygon`: one polygon's scan conversion, which the hemicube of
   `kernels.hemicube` calls too). An edge
   table of its non-horizontal edges; for each scan line, the active edges (top <= y < bottom) give crossings
   (x by direct evaluation from the edge's end points, so two polygons sharing an edge compute the same x
   bit for bit, and depth/attributes stepped incrementally down each edge); crossings sorted by x, spans filled
   between pairs (even–odd, so concave polygons fill correctly too), depth and attributes stepped incrementally
   along each span. The z-buffer keeps the nearest sample; the G-buffer keeps its polygon id and attributes.
4. Shading happens in the method (`methods.raster`): flat, Gouraud or Phong, through the one illumination model.

Conventions. Pixel (c, r) is sampled at (c + jx, r + jy) — the centre (0.5, 0.5) with one sample per pixel.
Fill rule (top-left): a sample is covered when top <= y < bottom and left <= x < right, so polygons that share
an edge cover each sample on it exactly once. The depth key is 1/W for perspective (linear in screen space,
larger is nearer) and −D for orthographic views. Attributes are interpolated as A/W and 1/W and divided per
pixel (perspective-correct); with `persp` off they are interpolated linearly in screen space, as the textbook's
scan-line algorithm does, which distorts them under perspective.
"""

import math

import numpy as np

from .jit import njit, njit_alloc, njit_inline, njit_serial
from .layout import CAM_HALF_SIZE, CAM_ORTHO, CAM_TAN_HALF_FOV, MAT_CUTOUT
from .texture import is_hole

#: Rows per band: the unit of parallel work in the raster pass.
BAND = 8
#: Most vertices a polygon may have after near-plane clipping (input polygons have at most MAX_VERTS - 1).
MAX_VERTS = 16
#: Rasterize into the z-buffer and G-buffer / only count how many polygons cover each sample (tests).
MODE_DEPTH = 0
MODE_COUNT = 1
BIN_CHUNK = 4096


@njit_serial
def project_vertices(positions, cam_vecs, cam_params, width, height, near, clip, screen):
    """clip[i] = (X, Y, W, D); screen[i] = (x, y, key, 1/W) for vertices with D >= near (NaN-free otherwise).
    Serial: a million vertices take about 8 ms on one core."""
    ortho = cam_params[CAM_ORTHO] != 0.0
    aspect = width / height
    if ortho:
        sx_scale = 1.0 / (aspect * cam_params[CAM_HALF_SIZE])
        sy_scale = 1.0 / cam_params[CAM_HALF_SIZE]
    else:
        sx_scale = 1.0 / (aspect * cam_params[CAM_TAN_HALF_FOV])
        sy_scale = 1.0 / cam_params[CAM_TAN_HALF_FOV]
    for i in range(positions.shape[0]):
        rx = positions[i, 0] - cam_vecs[0, 0]
        ry = positions[i, 1] - cam_vecs[0, 1]
        rz = positions[i, 2] - cam_vecs[0, 2]
        cx = rx * cam_vecs[1, 0] + ry * cam_vecs[1, 1] + rz * cam_vecs[1, 2]
        cy = rx * cam_vecs[2, 0] + ry * cam_vecs[2, 1] + rz * cam_vecs[2, 2]
        d = -(rx * cam_vecs[3, 0] + ry * cam_vecs[3, 1] + rz * cam_vecs[3, 2])
        X = cx * sx_scale
        Y = cy * sy_scale
        W = 1.0 if ortho else d
        clip[i, 0] = X
        clip[i, 1] = Y
        clip[i, 2] = W
        clip[i, 3] = d
        if d >= near:
            screen[i, 0], screen[i, 1], screen[i, 2], screen[i, 3] = _to_screen(X, Y, W, d, ortho, width, height)
        else:
            screen[i, 0] = screen[i, 1] = screen[i, 2] = screen[i, 3] = 0.0


@njit
def _to_screen(X, Y, W, d, ortho, width, height):
    inv_w = 1.0 / W
    x = (X * inv_w + 1.0) * 0.5 * width
    y = (1.0 - Y * inv_w) * 0.5 * height
    key = -d if ortho else inv_w
    return x, y, key, inv_w


@njit
def clip_polygon(prim, prim_start, prim_index, clip, near, ortho, width, height, px, py, src, tmp_c):
    """Sutherland–Hodgman against the near plane (D >= near) for a polygon that crosses it, in clip space where
    every attribute is linear. Fills px, py (pixels), tmp_c (clip-space vertices; column 4 the crossing
    parameter t) and src (the inside and outside vertex each output vertex lies between). The crossing of an
    edge is computed from its inside end point, whichever way the polygon runs, so neighbours agree on it.
    Returns the output vertex count."""
    start = prim_start[prim]
    n = prim_start[prim + 1] - start
    m = 0
    for k in range(n):
        a = prim_index[start + k]
        b = prim_index[start + (k + 1) % n]
        ca = clip[a, 3] - near
        cb = clip[b, 3] - near
        if ca >= 0.0:
            for c in range(4):
                tmp_c[m, c] = clip[a, c]
            src[m, 0] = a
            src[m, 1] = a
            tmp_c[m, 4] = 0.0
            m += 1
        if (ca >= 0.0) != (cb >= 0.0):
            i_in, i_out, c_in, c_out = (a, b, ca, cb) if ca >= 0.0 else (b, a, cb, ca)
            t = c_in / (c_in - c_out)
            for c in range(4):
                tmp_c[m, c] = clip[i_in, c] + t * (clip[i_out, c] - clip[i_in, c])
            tmp_c[m, 3] = max(tmp_c[m, 3], near)
            if not ortho:
                tmp_c[m, 2] = tmp_c[m, 3]
            src[m, 0] = i_in
            src[m, 1] = i_out
            tmp_c[m, 4] = t
            m += 1
    for k in range(m):
        x, y, _, _ = _to_screen(tmp_c[k, 0], tmp_c[k, 1], tmp_c[k, 2], tmp_c[k, 3], ortho, width, height)
        px[k] = x
        py[k] = y
    return m


@njit
def clipped_attributes(n, src, tmp_c, attrs, ortho, persp, width, height, F):
    """F[k] = (depth key, q, A·q) at each vertex of a clipped polygon (see clip_polygon)."""
    K = attrs.shape[1]
    for k in range(n):
        _, _, key, inv_w = _to_screen(tmp_c[k, 0], tmp_c[k, 1], tmp_c[k, 2], tmp_c[k, 3], ortho, width, height)
        q = inv_w if persp else 1.0
        F[k, 0] = key
        F[k, 1] = q
        i_in = src[k, 0]
        i_out = src[k, 1]
        t = tmp_c[k, 4]
        for a in range(K):
            F[k, 2 + a] = (attrs[i_in, a] + t * (attrs[i_out, a] - attrs[i_in, a])) * q


@njit
def signed_area2(n, px, py):
    """Twice the signed area of the screen polygon (pixel coordinates, y down): negative when the polygon is
    counter-clockwise as seen by the camera, i.e. front-facing."""
    s = 0.0
    for k in range(n):
        j = (k + 1) % n
        s += px[k] * py[j] - px[j] * py[k]
    return s


@njit_serial
def bin_prims(prim_start, prim_index, clip, screen, near, ortho, cull, width, height, jy, row_lo, row_hi, c0, c1):
    """Rows [row_lo, row_hi) whose sample points (y = r + jy) a polygon may cover, empty for culled ones, for
    the polygons of chunks c0 … c1−1 of BIN_CHUNK (`threads.parallel_for` over the chunks)."""
    for c in range(c0, c1):
        bin_chunk(c, prim_start, prim_index, clip, screen, near, ortho, cull, width, height, jy, row_lo, row_hi)


@njit_alloc
def bin_chunk(c, prim_start, prim_index, clip, screen, near, ortho, cull, width, height, jy, row_lo, row_hi):
    """Rows to scan for the polygons of one chunk (see bin_prims)."""
    n_prims = prim_start.shape[0] - 1
    chunk = BIN_CHUNK
    px = np.empty(MAX_VERTS)
    py = np.empty(MAX_VERTS)
    src = np.empty((MAX_VERTS, 2), np.int64)
    tmp_c = np.empty((MAX_VERTS, 5))
    for prim in range(c * chunk, min(n_prims, (c + 1) * chunk)):
        row_lo[prim] = 0
        row_hi[prim] = 0
        start = prim_start[prim]
        n = prim_start[prim + 1] - start
        inside = 0
        for k in range(n):
            v = prim_index[start + k]
            if clip[v, 3] >= near:
                inside += 1
            px[k] = screen[v, 0]
            py[k] = screen[v, 1]
        if inside == 0:
            continue
        if inside < n:
            n = clip_polygon(prim, prim_start, prim_index, clip, near, ortho, width, height, px, py, src, tmp_c)
        if n < 3:
            continue
        if cull and signed_area2(n, px, py) >= 0.0:
            continue
        y_min = py[0]
        y_max = py[0]
        x_min = px[0]
        x_max = px[0]
        for k in range(1, n):
            y_min = min(y_min, py[k])
            y_max = max(y_max, py[k])
            x_min = min(x_min, px[k])
            x_max = max(x_max, px[k])
        if x_max < 0.0 or x_min > width or not (y_max >= 0.0 and y_min <= height):
            continue
        lo = max(0.0, math.ceil(y_min - jy))
        hi = min(float(height), math.ceil(y_max - jy))
        if hi > lo:
            row_lo[prim] = np.int32(lo)
            row_hi[prim] = np.int32(hi)


@njit_alloc
def fill_bins(row_lo, row_hi, n_bands):
    """Polygons sorted into bands of BAND rows (a counting sort; original order kept within each band)."""
    counts = np.zeros(n_bands + 1, np.int64)
    for p in range(row_lo.shape[0]):
        if row_hi[p] > row_lo[p]:
            for b in range(row_lo[p] // BAND, (row_hi[p] - 1) // BAND + 1):
                counts[b + 1] += 1
    for b in range(n_bands):
        counts[b + 1] += counts[b]
    prims = np.empty(counts[n_bands], np.int32)
    fill = counts[:n_bands].copy()
    for p in range(row_lo.shape[0]):
        if row_hi[p] > row_lo[p]:
            for b in range(row_lo[p] // BAND, (row_hi[p] - 1) // BAND + 1):
                prims[fill[b]] = p
                fill[b] += 1
    return counts, prims


@njit_serial
def raster_bands(bins, bin_prims_, prim_start, prim_index, clip, screen, attrs, near, ortho, persp,
                 width, height, jx, jy, row_lo, row_hi, mode, zbuf, ids, gbuf, count, tex, materials, prim_material,
                 uv_at, b0, b1):
    """The raster pass over bands b0 … b1−1 (`threads.parallel_for` over the bands): each band of BAND rows
    scan-converts its polygons into the buffers. In MODE_DEPTH
    it clears zbuf (−inf) and ids (−1) first; gbuf is written only where ids >= 0.

    Opacity cut-outs: a polygon whose material (materials[prim_material[prim]], float64 (nm, MAT_SIZE); int32
    (n_prims,)) has MAT_CUTOUT set writes no sample where its α (`texture.is_hole`, `tex` a view with tex_info and
    tex_pixels) at the interpolated (u, v) of attrs columns uv_at, uv_at + 1 is a hole, so what lies behind it
    stays in the buffers. uv_at −1: no cut-outs (the materials are not read); `tex` None: none ever (the test is
    not compiled)."""
    for band in range(b0, b1):
        raster_band(band, bins, bin_prims_, prim_start, prim_index, clip, screen, attrs, near, ortho, persp,
                    width, height, jx, jy, row_lo, row_hi, mode, zbuf, ids, gbuf, count, tex, materials,
                    prim_material, uv_at)


@njit_alloc
def raster_band(band, bins, bin_prims_, prim_start, prim_index, clip, screen, attrs, near, ortho, persp,
                width, height, jx, jy, row_lo, row_hi, mode, zbuf, ids, gbuf, count, tex, materials, prim_material,
                uv_at):
    """Scan-convert every polygon binned to one band of rows, in order (the same result on any thread)."""
    K = attrs.shape[1]
    KF = K + 2
    y0 = band * BAND
    y1 = min(height, y0 + BAND)
    px = np.empty(MAX_VERTS)
    py = np.empty(MAX_VERTS)
    src = np.empty((MAX_VERTS, 2), np.int64)
    tmp_c = np.empty((MAX_VERTS, 5))
    F = np.empty((MAX_VERTS, KF))
    # the layout of `edge_scratch`, allocated here rather than returned by it: the pass ran 3-5% faster so
    edges = (np.empty(MAX_VERTS), np.empty(MAX_VERTS), np.empty(MAX_VERTS), np.empty(MAX_VERTS),
             np.empty((MAX_VERTS, 2), np.int64), np.empty(MAX_VERTS, np.int64),
             np.empty((MAX_VERTS, KF)), np.empty((MAX_VERTS, KF)),
             np.empty(MAX_VERTS), np.empty(MAX_VERTS, np.int64), np.empty((2, KF)))
    if mode == MODE_DEPTH:  # clear this band's rows of the buffers (here, so that clearing runs in parallel)
        for r in range(y0, y1):
            for c in range(width):
                zbuf[r, c] = -np.inf
                ids[r, c] = -1
    for k in range(bins[band], bins[band + 1]):
        prim = bin_prims_[k]
        r0 = max(y0, row_lo[prim])
        r1 = min(y1, row_hi[prim])
        # the screen polygon (clipped against the near plane when it crosses it)
        start = prim_start[prim]
        n = prim_start[prim + 1] - start
        clipped = False
        for i in range(n):
            v = prim_index[start + i]
            px[i] = screen[v, 0]
            py[i] = screen[v, 1]
            if clip[v, 3] < near:
                clipped = True
        if clipped:
            n = clip_polygon(prim, prim_start, prim_index, clip, near, ortho, width, height, px, py, src, tmp_c)
        ne = setup_edges(n, px, py, edges)
        if mode == MODE_COUNT:
            count_polygon(ne, edges, r0, r1, width, jx, jy, count)
            continue
        r, nx = first_covered_row(ne, edges, r0, r1, width, jx, jy)
        if r >= r1:
            continue  # most small polygons cover no sample: their attributes are never set up
        # depth key, q and A·q at the vertices (q = 1/W, or 1 without perspective correction)
        if clipped:
            clipped_attributes(n, src, tmp_c, attrs, ortho, persp, width, height, F)
        else:
            for i in range(n):
                v = prim_index[start + i]
                q = screen[v, 3] if persp else 1.0
                F[i, 0] = screen[v, 2]
                F[i, 1] = q
                for a in range(K):
                    F[i, 2 + a] = attrs[v, a] * q
        if tex is not None and uv_at >= 0 and materials[prim_material[prim], MAT_CUTOUT] != 0.0:
            fill_polygon(ne, edges, nx, F, r, r1, width, jx, jy, prim, zbuf, ids, gbuf,
                         (tex, materials[prim_material[prim]], uv_at))
        else:
            fill_polygon(ne, edges, nx, F, r, r1, width, jx, jy, prim, zbuf, ids, gbuf, None)


@njit_inline
def _in_hole(cutout, xF):
    """Whether the sample whose (key, q, A·q) xF[0] holds falls in a hole of the polygon's opacity cut-out."""
    tex, mat, uv_at = cutout
    inv_q = 1.0 / xF[0, 1]
    p = (xF[0, 2] * inv_q, xF[0, 3] * inv_q, xF[0, 4] * inv_q)
    return is_hole(tex, mat, xF[0, 2 + uv_at] * inv_q, xF[0, 3 + uv_at] * inv_q, p)


# ------------------------------------------------------------------ the scan conversion of one polygon
# Shared by `raster_band` and the hemicube (`kernels.hemicube`); each step one function, inlined (LLVM
# alwaysinline, no runtime): a call that is not inlined passes each array as a dozen scalars and, with the
# runtime, counts its references, which costs more than the scan conversion of a small polygon itself (the pass
# once ran 4x slower with its per-polygon work in ordinary helper functions). A caller runs setup_edges, then
# first_covered_row, sets the vertex values F up only if the polygon covers a sample, then fill_polygon.


@njit_alloc
def edge_scratch(kf):
    """Working arrays of the scan converter for polygons of up to MAX_VERTS vertices and `kf` values per vertex
    (the depth key, q, then the attributes times q): the `edges` tuple of `setup_edges`, `first_covered_row`,
    `count_polygon` and `fill_polygon`. Per edge: top y, bottom y, x at the top, dx/dy (float64 (MAX_VERTS,)
    each), its top and bottom vertex (int64 (MAX_VERTS, 2)), the last row its values were set for (int64
    (MAX_VERTS,)), those values and their steps per row (float64 (MAX_VERTS, kf) each); per scan line the
    crossings' x and edges (float64 and int64 (MAX_VERTS,)); along a span the values and their steps per pixel
    (float64 (2, kf))."""
    return (np.empty(MAX_VERTS), np.empty(MAX_VERTS), np.empty(MAX_VERTS), np.empty(MAX_VERTS),
            np.empty((MAX_VERTS, 2), np.int64), np.empty(MAX_VERTS, np.int64),
            np.empty((MAX_VERTS, kf)), np.empty((MAX_VERTS, kf)),
            np.empty(MAX_VERTS), np.empty(MAX_VERTS, np.int64), np.empty((2, kf)))


@njit_inline
def setup_edges(n, px, py, edges):
    """The edge table of the polygon px[:n], py[:n] (pixels): its non-horizontal edges, each from its top
    (smaller y) end point to its bottom one. Returns the edge count."""
    e_top, e_bot, e_x, e_dx, e_v, e_row, _, _, _, _, _ = edges
    ne = 0
    for i in range(n):
        j = i + 1 if i + 1 < n else 0
        if py[i] == py[j]:
            continue
        top, bot = (i, j) if py[i] < py[j] else (j, i)
        e_top[ne] = py[top]
        e_bot[ne] = py[bot]
        e_x[ne] = px[top]
        e_dx[ne] = (px[bot] - px[top]) / (py[bot] - py[top])
        e_v[ne, 0] = top
        e_v[ne, 1] = bot
        e_row[ne] = -2
        ne += 1
    return ne


@njit_inline
def row_crossings(ne, edges, yc):
    """The active edges at scan line y = yc (top <= yc < bottom) and their crossings, sorted by x into the
    `edges` tuple's crossing arrays (insertion sort: two for a triangle). x is evaluated directly from the edge's
    end points, so two polygons sharing an edge compute the same x bit for bit. Returns the crossing count."""
    e_top, e_bot, e_x, e_dx, _, _, _, _, xs, order, _ = edges
    nx = 0
    for e in range(ne):
        if e_top[e] <= yc < e_bot[e]:
            xv = e_x[e] + (yc - e_top[e]) * e_dx[e]
            j = nx - 1
            while j >= 0 and xs[j] > xv:
                xs[j + 1] = xs[j]
                order[j + 1] = order[j]
                j -= 1
            xs[j + 1] = xv
            order[j + 1] = e
            nx += 1
    return nx


@njit_inline
def span_columns(xl, xr, width, jx):
    """Columns [c0, c1) whose sample points (x = c + jx) lie in the span xl <= x < xr, within [0, width)."""
    c0 = max(0, int(math.ceil(xl - jx)))
    c1 = min(width, int(math.ceil(xr - jx)))
    return c0, c1


@njit_inline
def first_covered_row(ne, edges, r0, r1, width, jx, jy):
    """(r, nx): the first row in [r0, r1) where the polygon covers a sample (spans between pairs of crossings,
    even-odd) and its crossing count, its crossings left in `edges` for `fill_polygon` to start from; (r1, 0)
    when it covers none."""
    xs = edges[8]
    for r in range(r0, r1):
        nx = row_crossings(ne, edges, r + jy)
        for s in range(0, nx - 1, 2):
            c0, c1 = span_columns(xs[s], xs[s + 1], width, jx)
            if c1 > c0:
                return r, nx
    return r1, 0


@njit_inline
def count_polygon(ne, edges, r0, r1, width, jx, jy, count):
    """count[r, c] += 1 at every sample of rows [r0, r1) the polygon covers (no depth test)."""
    xs = edges[8]
    for r in range(r0, r1):
        nx = row_crossings(ne, edges, r + jy)
        for s in range(0, nx - 1, 2):
            c0, c1 = span_columns(xs[s], xs[s + 1], width, jx)
            for c in range(c0, c1):
                count[r, c] += 1


@njit_inline
def fill_polygon(ne, edges, nx0, F, r0, r1, width, jx, jy, item, zbuf, ids, gbuf, cutout):
    """The z-buffer pass of one polygon over rows [r0, r1): where its depth key is larger (nearer) than
    zbuf[r, c], zbuf[r, c] = key, ids[r, c] = item and gbuf[r, c, a] = (A·q)/q for the F.shape[1] - 2 attributes.
    `cutout` None, or (tex, material row, uv_at) for a polygon with an opacity cut-out: samples where the
    attributes uv_at, uv_at + 1 (its (u, v), perspective-correct as the others) fall in a hole
    (`texture.is_hole`, at the position in attributes 0-2) are discarded, z-buffer and all.
    The crossings of row r0 must be in `edges` already, nx0 of them, as `first_covered_row` leaves them.

    F float64 (>= n, KF): (key, q, A·q) at the polygon's vertices, all linear in screen space; each is stepped
    incrementally down each edge and along each span. zbuf float64 (H, W), ids int32 (H, W), gbuf float32
    (H, W, KF - 2) with H >= r1."""
    e_top, e_bot, _, _, e_v, e_row, e_F, e_dF, xs, order, xF = edges
    KF = F.shape[1]
    K = KF - 2
    nx = nx0
    for r in range(r0, r1):
        yc = r + jy
        if r > r0:
            nx = row_crossings(ne, edges, yc)
        for s in range(0, nx - 1, 2):
            xl = xs[s]
            xr = xs[s + 1]
            c0, c1 = span_columns(xl, xr, width, jx)
            if c1 <= c0:
                continue
            # each edge's values at this scan line: one step from the last, or evaluated where it starts
            for side in range(2):
                e = order[s + side]
                if e_row[e] == r - 1:
                    for a in range(KF):
                        e_F[e, a] += e_dF[e, a]
                elif e_row[e] != r:
                    top = e_v[e, 0]
                    if e_row[e] == -2:  # the edge's first use: its steps per scan line (an edge may never be used)
                        inv_dy = 1.0 / (e_bot[e] - e_top[e])
                        bot = e_v[e, 1]
                        for a in range(KF):
                            e_dF[e, a] = (F[bot, a] - F[top, a]) * inv_dy
                    dy = yc - e_top[e]
                    for a in range(KF):
                        e_F[e, a] = F[top, a] + dy * e_dF[e, a]
                e_row[e] = r
            # along the span: start at the first sample, then one step per pixel
            el = order[s]
            er = order[s + 1]
            inv_dx = 1.0 / (xr - xl)
            off = c0 + jx - xl
            for a in range(KF):
                d = (e_F[er, a] - e_F[el, a]) * inv_dx
                xF[1, a] = d
                xF[0, a] = e_F[el, a] + off * d
            for c in range(c0, c1):
                key = xF[0, 0]
                if key > zbuf[r, c]:
                    covered = True
                    if cutout is not None:  # (pruned at compile time for the polygons without one)
                        covered = not _in_hole(cutout, xF)
                    if covered:
                        zbuf[r, c] = key
                        ids[r, c] = item
                        inv_q = 1.0 / xF[0, 1]
                        for a in range(K):
                            gbuf[r, c, a] = xF[0, 2 + a] * inv_q
                for a in range(KF):
                    xF[0, a] += xF[1, a]
