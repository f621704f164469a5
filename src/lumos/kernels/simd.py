"""Explicit SIMD: the slab test of one ray against all the child boxes of a wide BVH node in one go, and the
watertight test of one ray against the four triangles of a packed leaf.

Numba does not vectorise a traversal loop by itself (each node is one iteration with a data-dependent branch),
so `wide_box_test` is a Numba `@intrinsic` whose code generator writes the LLVM vector IR directly (llvmlite):
one `<WIDE x float>` load per bound row of the node, widened to `<WIDE x double>`, and the slab arithmetic on all
the boxes at once (`vcvtps2pd`, `vsubpd`, `vmulpd`, `vmaxpd`, `vminpd`, one `vcmplepd`). It computes exactly what
the scalar `intersect.intersect_node_box` computes, lane by lane, in the same order and precision: float64 from
float32 bounds, t_far scaled by 1 + 2γ(3), entry clamped to 0 (Ize 2013; see `intersect`), so the wide tree is
exactly as conservative as the binary one. Min and max are `select(fcmp)` (one instruction each), not
`llvm.minnum` (which adds NaN fix-ups); the bounds are never NaN and empty child slots hold inverted infinite
boxes, which every ray misses.

Node layout (`layout.WIDE_*`): 8·WIDE float32 per node, rows of WIDE lanes: min x, min y, min z, max x, max y,
max z, then the children's links (int32 bits). The near plane of each axis is the min row where the direction is
positive and the max row where it is negative: the caller passes the row offsets (`wide_setup`), so the kernel
needs no per-axis select. `lowest_bit` (LLVM's cttz) walks the set bits of a hit mask.
"""

from llvmlite import ir
from numba import types
from numba.core import cgutils
from numba.extending import intrinsic, overload

from .intersect import ROBUST_FAR
from .jit import njit_inline
from .layout import WIDE

_F32x4 = ir.VectorType(ir.FloatType(), 4)
_F64x4 = ir.VectorType(ir.DoubleType(), 4)
_F32xW = ir.VectorType(ir.FloatType(), WIDE)
_F64xW = ir.VectorType(ir.DoubleType(), WIDE)


def _splat(builder, value, lanes=4):
    vty = ir.VectorType(ir.DoubleType(), lanes)
    vec = builder.insert_element(ir.Constant(vty, ir.Undefined), value, ir.Constant(ir.IntType(32), 0))
    return builder.shuffle_vector(vec, ir.Constant(vty, ir.Undefined), ir.Constant(ir.VectorType(ir.IntType(32), lanes),
                                                                                   [0] * lanes))


def _vmax(builder, a, b):
    return builder.select(builder.fcmp_ordered(">", a, b), a, b)


def _vmin(builder, a, b):
    return builder.select(builder.fcmp_ordered("<", a, b), a, b)


@njit_inline
def wide_setup(rb):
    """The row offsets (near_x, near_y, near_z) of `wide_box_test` from `intersect.box_setup`'s result rb."""
    return WIDE * rb[6], WIDE * rb[7], WIDE * rb[8]


def wide_box_test(nodes, j, near_x, near_y, near_z, ox, oy, oz, ix, iy, iz, t_max, entry, at):
    """Bit k of the mask returned is set if the ray meets child box k of wide node j before t_max; box k's entry
    distance (clamped to 0) is stored in entry[at + k] (float64, k < WIDE), whether it is hit or not. `nodes` is
    float32 (n, WIDE_SIZE) C-contiguous; near_* are the float offsets of each axis's near row (`wide_setup`), the
    far row being the other one.

    This Python body is the interpreted twin (NUMBA_DISABLE_JIT=1, and the reference in tests); compiled code
    gets `_wide_box_vector` through the overload below, which stores the entry distances with one vector store
    (read back lane by lane, a load from the store buffer: cheaper than a switch over the lanes)."""
    row = nodes[j]
    w = WIDE
    mask = 0
    for k in range(w):
        t_near = max(max((float(row[near_x + k]) - ox) * ix, (float(row[near_y + k]) - oy) * iy),
                     max((float(row[near_z + k]) - oz) * iz, 0.0))
        t_far = min(min((float(row[3 * w - near_x + k]) - ox) * ix, (float(row[5 * w - near_y + k]) - oy) * iy),
                    (float(row[7 * w - near_z + k]) - oz) * iz) * ROBUST_FAR
        if entry is not None:
            entry[at + k] = t_near
        if t_near <= min(t_far, t_max):
            mask |= 1 << k
    return mask


def wide_box_mask(nodes, j, near_x, near_y, near_z, ox, oy, oz, ix, iy, iz, t_max):
    """`wide_box_test`'s mask alone (any-order walks need no entry distances)."""
    return wide_box_test(nodes, j, near_x, near_y, near_z, ox, oy, oz, ix, iy, iz, t_max, None, 0)


@overload(wide_box_test, inline="always")
def _wide_box_test_jit(nodes, j, near_x, near_y, near_z, ox, oy, oz, ix, iy, iz, t_max, entry, at):
    def impl(nodes, j, near_x, near_y, near_z, ox, oy, oz, ix, iy, iz, t_max, entry, at):
        return _wide_box_vector(nodes, j, near_x, near_y, near_z, ox, oy, oz, ix, iy, iz, t_max, entry, at)

    return impl


@overload(wide_box_mask, inline="always")
def _wide_box_mask_jit(nodes, j, near_x, near_y, near_z, ox, oy, oz, ix, iy, iz, t_max):
    def impl(nodes, j, near_x, near_y, near_z, ox, oy, oz, ix, iy, iz, t_max):
        return _wide_box_vector(nodes, j, near_x, near_y, near_z, ox, oy, oz, ix, iy, iz, t_max, None, 0)

    return impl


@intrinsic
def _wide_box_vector(typingctx, nodes, j, near_x, near_y, near_z, ox, oy, oz, ix, iy, iz, t_max, entry, at):
    """`wide_box_test` in LLVM vector IR (entry None: no store)."""
    sig = types.int64(nodes, j, near_x, near_y, near_z, ox, oy, oz, ix, iy, iz, t_max, entry, at)
    store = not isinstance(entry, (types.NoneType, types.Omitted))

    def codegen(context, builder, signature, args):
        nodes_v, j_v, nx_v, ny_v, nz_v, ox_v, oy_v, oz_v, ix_v, iy_v, iz_v, tmax_v, entry_v, at_v = args
        ary = context.make_array(signature.args[0])(context, builder, nodes_v)
        i64 = ir.IntType(64)
        row = cgutils.get_item_pointer(context, builder, signature.args[0], ary, [j_v, ir.Constant(i64, 0)],
                                       wraparound=False)

        def load(offset):  # WIDE float32 at row + offset (floats), widened to double
            ptr = builder.bitcast(builder.gep(row, [offset]), _F32xW.as_pointer())
            return builder.fpext(builder.load(ptr, align=4), _F64xW)

        def plane(offset, origin, inv):
            return builder.fmul(builder.fsub(load(offset), _splat(builder, origin, WIDE)),
                                _splat(builder, inv, WIDE))

        far_x = builder.sub(ir.Constant(i64, 3 * WIDE), nx_v)  # min row <-> max row, axis by axis
        far_y = builder.sub(ir.Constant(i64, 5 * WIDE), ny_v)
        far_z = builder.sub(ir.Constant(i64, 7 * WIDE), nz_v)
        t_near = _vmax(builder,
                       _vmax(builder, plane(nx_v, ox_v, ix_v), plane(ny_v, oy_v, iy_v)),
                       _vmax(builder, plane(nz_v, oz_v, iz_v), ir.Constant(_F64xW, [0.0] * WIDE)))
        t_far = _vmin(builder, _vmin(builder, plane(far_x, ox_v, ix_v), plane(far_y, oy_v, iy_v)),
                      plane(far_z, oz_v, iz_v))
        t_far = builder.fmul(t_far, ir.Constant(_F64xW, [ROBUST_FAR] * WIDE))
        hit = builder.fcmp_ordered("<=", t_near, _vmin(builder, t_far, _splat(builder, tmax_v, WIDE)))
        if store:
            out = context.make_array(signature.args[12])(context, builder, entry_v)
            at_i = context.cast(builder, at_v, signature.args[13], types.int64)
            ptr = cgutils.get_item_pointer(context, builder, signature.args[12], out, [at_i], wraparound=False)
            builder.store(t_near, builder.bitcast(ptr, _F64xW.as_pointer()), align=8)
        return builder.zext(builder.bitcast(hit, ir.IntType(WIDE)), i64)

    return sig, codegen


def lowest_bit(mask):
    """The index of the lowest set bit of mask (> 0): LLVM's cttz when compiled."""
    return (mask & -mask).bit_length() - 1


@overload(lowest_bit, inline="always")
def _lowest_bit_jit(mask):
    def impl(mask):
        return _cttz(mask)

    return impl


@intrinsic
def _cttz(typingctx, mask):
    sig = types.int64(types.int64)

    def codegen(context, builder, signature, args):
        i64 = ir.IntType(64)
        fn = builder.module.declare_intrinsic("llvm.cttz", [i64], ir.FunctionType(i64, [i64, ir.IntType(1)]))
        return builder.call(fn, [args[0], ir.Constant(ir.IntType(1), 1)])  # 1: mask == 0 is never asked

    return sig, codegen


def tri4_test(leaves, j, kx, ky, kz, sx, sy, sz, okx, oky, okz, t_max):
    """(mask, t0, t1, t2, t3, b1_0, ..., b1_3, b2_0, ..., b2_3): the watertight test
    (`intersect.intersect_triangle`) of one ray against the four triangles of packed leaf j at once; bit k of
    mask is set where triangle k is hit with 0 < t <= t_max, tk its distance and b1_k, b2_k its barycentrics. `leaves` is float32 (n, >= 36): rows of four lanes v0.x, v0.y, v0.z, v1.x, ..., v2.z; kx, ky, kz
    and sx, sy, sz are the ray's shear constants (`intersect.triangle_setup`), okx, oky, okz its origin's
    components on those axes. Lane for lane the same operations in the same order and precision as the scalar
    test, so the same triangles are hit at the same distances and barycentrics, bit for bit.

    This Python body is the interpreted twin; compiled code gets `_tri4_vector` through the overload below."""
    row = leaves[j]
    mask = 0
    out = [0.0] * 12
    for k in range(4):
        ax = float(row[4 * kx + k]) - okx
        ay = float(row[4 * ky + k]) - oky
        az = float(row[4 * kz + k]) - okz
        bx = float(row[12 + 4 * kx + k]) - okx
        by = float(row[12 + 4 * ky + k]) - oky
        bz = float(row[12 + 4 * kz + k]) - okz
        cx = float(row[24 + 4 * kx + k]) - okx
        cy = float(row[24 + 4 * ky + k]) - oky
        cz = float(row[24 + 4 * kz + k]) - okz
        ax, ay = ax - sx * az, ay - sy * az
        bx, by = bx - sx * bz, by - sy * bz
        cx, cy = cx - sx * cz, cy - sy * cz
        e0 = cx * by - cy * bx
        e1 = ax * cy - ay * cx
        e2 = bx * ay - by * ax
        if (e0 < 0.0 or e1 < 0.0 or e2 < 0.0) and (e0 > 0.0 or e1 > 0.0 or e2 > 0.0):
            continue
        det = e0 + e1 + e2
        if det == 0.0:
            continue
        t_scaled = (e0 * az + e1 * bz + e2 * cz) * sz
        if det < 0.0:
            if t_scaled >= 0.0 or t_scaled < t_max * det:
                continue
        elif t_scaled <= 0.0 or t_scaled > t_max * det:
            continue
        inv = 1.0 / det
        out[k], out[4 + k], out[8 + k] = t_scaled * inv, e1 * inv, e2 * inv
        mask |= 1 << k
    return (mask, out[0], out[1], out[2], out[3], out[4], out[5], out[6], out[7], out[8], out[9], out[10],
            out[11])


@overload(tri4_test, inline="always")
def _tri4_test_jit(leaves, j, kx, ky, kz, sx, sy, sz, okx, oky, okz, t_max):
    def impl(leaves, j, kx, ky, kz, sx, sy, sz, okx, oky, okz, t_max):
        return _tri4_vector(leaves, j, kx, ky, kz, sx, sy, sz, okx, oky, okz, t_max)

    return impl


@intrinsic
def _tri4_vector(typingctx, leaves, j, kx, ky, kz, sx, sy, sz, okx, oky, okz, t_max):
    """`tri4_test` in LLVM vector IR."""
    f64 = types.float64
    sig = types.Tuple((types.int64,) + (f64,) * 12)(leaves, j, kx, ky, kz, sx, sy, sz, okx, oky, okz, t_max)

    def codegen(context, builder, signature, args):
        leaves_v, j_v, kx_v, ky_v, kz_v, sx_v, sy_v, sz_v, okx_v, oky_v, okz_v, tmax_v = args
        ary = context.make_array(signature.args[0])(context, builder, leaves_v)
        i64 = ir.IntType(64)
        row = cgutils.get_item_pointer(context, builder, signature.args[0], ary, [j_v, ir.Constant(i64, 0)],
                                       wraparound=False)
        four = ir.Constant(i64, 4)

        def load(vertex, axis, origin):  # lanes of vertex.axis, widened, minus the origin's component
            offset = builder.add(ir.Constant(i64, 12 * vertex), builder.mul(axis, four))
            ptr = builder.bitcast(builder.gep(row, [offset]), _F32x4.as_pointer())
            return builder.fsub(builder.fpext(builder.load(ptr, align=4), _F64x4), _splat(builder, origin))

        sx4, sy4, sz4 = _splat(builder, sx_v), _splat(builder, sy_v), _splat(builder, sz_v)
        fsub, fmul, fadd = builder.fsub, builder.fmul, builder.fadd
        ax, ay, az = load(0, kx_v, okx_v), load(0, ky_v, oky_v), load(0, kz_v, okz_v)
        bx, by, bz = load(1, kx_v, okx_v), load(1, ky_v, oky_v), load(1, kz_v, okz_v)
        cx, cy, cz = load(2, kx_v, okx_v), load(2, ky_v, oky_v), load(2, kz_v, okz_v)
        ax, ay = fsub(ax, fmul(sx4, az)), fsub(ay, fmul(sy4, az))
        bx, by = fsub(bx, fmul(sx4, bz)), fsub(by, fmul(sy4, bz))
        cx, cy = fsub(cx, fmul(sx4, cz)), fsub(cy, fmul(sy4, cz))
        e0 = fsub(fmul(cx, by), fmul(cy, bx))
        e1 = fsub(fmul(ax, cy), fmul(ay, cx))
        e2 = fsub(fmul(bx, ay), fmul(by, ax))
        zero = ir.Constant(_F64x4, [0.0] * 4)
        lt = lambda a, b: builder.fcmp_ordered("<", a, b)  # noqa: E731
        gt = lambda a, b: builder.fcmp_ordered(">", a, b)  # noqa: E731
        any_neg = builder.or_(builder.or_(lt(e0, zero), lt(e1, zero)), lt(e2, zero))
        any_pos = builder.or_(builder.or_(gt(e0, zero), gt(e1, zero)), gt(e2, zero))
        det = fadd(fadd(e0, e1), e2)
        t_scaled = fmul(fadd(fadd(fmul(e0, az), fmul(e1, bz)), fmul(e2, cz)), sz4)
        limit = fmul(_splat(builder, tmax_v), det)
        negative = lt(det, zero)
        # det < 0: reject t_scaled >= 0 or t_scaled < limit; det >= 0: reject t_scaled <= 0 or t_scaled > limit
        reject_neg = builder.or_(builder.fcmp_ordered(">=", t_scaled, zero), lt(t_scaled, limit))
        reject_pos = builder.or_(builder.fcmp_ordered("<=", t_scaled, zero), gt(t_scaled, limit))
        reject = builder.or_(builder.and_(any_neg, any_pos), builder.fcmp_ordered("==", det, zero))
        reject = builder.or_(reject, builder.select(negative, reject_neg, reject_pos))
        hit = builder.xor(reject, ir.Constant(ir.VectorType(ir.IntType(1), 4), [1, 1, 1, 1]))
        inv = builder.fdiv(ir.Constant(_F64x4, [1.0] * 4), det)
        mask = builder.zext(builder.bitcast(hit, ir.IntType(4)), i64)
        lanes = [builder.extract_element(vec, ir.Constant(ir.IntType(32), k))
                 for vec in (fmul(t_scaled, inv), fmul(e1, inv), fmul(e2, inv)) for k in range(4)]
        return context.make_tuple(builder, signature.return_type, [mask] + lanes)

    return sig, codegen
