"""Explicit SIMD: the slab test of one ray against the four child boxes of a wide BVH node in one go.

Numba does not vectorise a traversal loop by itself (each node is one iteration with a data-dependent branch),
so `box4_test` is a Numba `@intrinsic` whose code generator writes the LLVM vector IR directly (llvmlite): one
`<4 x float>` load per bound row of the node, widened to `<4 x double>`, and the slab arithmetic on all four
boxes at once (`vcvtps2pd`, `vsubpd`, `vmulpd`, `vmaxpd`, `vminpd`, one `vcmplepd`). It computes exactly what the
scalar `intersect.intersect_node_box` computes, lane by lane, in the same order and precision: float64 from
float32 bounds, t_far scaled by 1 + 2γ(3), entry clamped to 0 (Ize 2013; see `intersect`), so the wide tree is
exactly as conservative as the binary one. Min and max are `select(fcmp)` (one instruction each), not
`llvm.minnum` (which adds NaN fix-ups); the bounds are never NaN and empty child slots hold inverted infinite
boxes, which every ray misses.

Node layout (`layout.WIDE_*`): 32 float32 per node, rows of four lanes: min x, min y, min z, max x, max y, max z,
then the children's links (int32 bits). The near plane of each axis is the min row where the direction is
positive and the max row where it is negative: the caller passes the row offsets (`wide_setup`), so the kernel
needs no per-axis select.
"""

from llvmlite import ir
from numba import types
from numba.core import cgutils
from numba.extending import intrinsic, overload

from .intersect import _ROBUST_FAR

_F32x4 = ir.VectorType(ir.FloatType(), 4)
_F64x4 = ir.VectorType(ir.DoubleType(), 4)


def _splat(builder, value):
    vec = builder.insert_element(ir.Constant(_F64x4, ir.Undefined), value, ir.Constant(ir.IntType(32), 0))
    return builder.shuffle_vector(vec, ir.Constant(_F64x4, ir.Undefined), ir.Constant(ir.VectorType(ir.IntType(32), 4),
                                                                                      [0, 0, 0, 0]))


def _vmax(builder, a, b):
    return builder.select(builder.fcmp_ordered(">", a, b), a, b)


def _vmin(builder, a, b):
    return builder.select(builder.fcmp_ordered("<", a, b), a, b)


def box4_test(nodes, j, near_x, near_y, near_z, ox, oy, oz, ix, iy, iz, t_max):
    """(mask, t0, t1, t2, t3): bit k of mask is set if the ray meets child box k of wide node j before t_max;
    tk is its entry distance (clamped to 0). `nodes` is float32 (n, 32) C-contiguous; near_* are the float
    offsets of each axis's near row (0/12, 4/16, 8/20: 4× `intersect.box_setup`'s near columns), the far row
    being the other one.

    This Python body is the interpreted twin (NUMBA_DISABLE_JIT=1, and the reference in tests); compiled code
    gets `_box4_vector` through the overload below."""
    row = nodes[j]
    mask = 0
    entry = [0.0, 0.0, 0.0, 0.0]
    for k in range(4):
        t_near = max(max((float(row[near_x + k]) - ox) * ix, (float(row[near_y + k]) - oy) * iy),
                     max((float(row[near_z + k]) - oz) * iz, 0.0))
        t_far = min(min((float(row[12 - near_x + k]) - ox) * ix, (float(row[20 - near_y + k]) - oy) * iy),
                    (float(row[28 - near_z + k]) - oz) * iz) * _ROBUST_FAR
        entry[k] = t_near
        if t_near <= min(t_far, t_max):
            mask |= 1 << k
    return mask, entry[0], entry[1], entry[2], entry[3]


@overload(box4_test, inline="always")
def _box4_test_jit(nodes, j, near_x, near_y, near_z, ox, oy, oz, ix, iy, iz, t_max):
    def impl(nodes, j, near_x, near_y, near_z, ox, oy, oz, ix, iy, iz, t_max):
        return _box4_vector(nodes, j, near_x, near_y, near_z, ox, oy, oz, ix, iy, iz, t_max)

    return impl


@intrinsic
def _box4_vector(typingctx, nodes, j, near_x, near_y, near_z, ox, oy, oz, ix, iy, iz, t_max):
    """`box4_test` in LLVM vector IR."""
    f64 = types.float64
    sig = types.Tuple((types.int64, f64, f64, f64, f64))(nodes, j, near_x, near_y, near_z, ox, oy, oz, ix, iy, iz,
                                                          t_max)

    def codegen(context, builder, signature, args):
        nodes_v, j_v, nx_v, ny_v, nz_v, ox_v, oy_v, oz_v, ix_v, iy_v, iz_v, tmax_v = args
        ary = context.make_array(signature.args[0])(context, builder, nodes_v)
        zero = ir.Constant(ir.IntType(64), 0)
        row = cgutils.get_item_pointer(context, builder, signature.args[0], ary, [j_v, zero], wraparound=False)

        def load(offset):  # four float32 at row + offset (floats), widened to double
            ptr = builder.bitcast(builder.gep(row, [offset]), _F32x4.as_pointer())
            return builder.fpext(builder.load(ptr, align=4), _F64x4)

        def plane(offset, origin, inv):
            return builder.fmul(builder.fsub(load(offset), _splat(builder, origin)), _splat(builder, inv))

        i64 = ir.IntType(64)
        twelve = ir.Constant(i64, 12)
        far_x = builder.sub(twelve, nx_v)                   # 0 <-> 12
        far_y = builder.sub(ir.Constant(i64, 20), ny_v)     # 4 <-> 16
        far_z = builder.sub(ir.Constant(i64, 28), nz_v)     # 8 <-> 20
        t_near = _vmax(builder,
                       _vmax(builder, plane(nx_v, ox_v, ix_v), plane(ny_v, oy_v, iy_v)),
                       _vmax(builder, plane(nz_v, oz_v, iz_v), ir.Constant(_F64x4, [0.0] * 4)))
        t_far = _vmin(builder, _vmin(builder, plane(far_x, ox_v, ix_v), plane(far_y, oy_v, iy_v)),
                      plane(far_z, oz_v, iz_v))
        t_far = builder.fmul(t_far, ir.Constant(_F64x4, [_ROBUST_FAR] * 4))
        hit = builder.fcmp_ordered("<=", t_near, _vmin(builder, t_far, _splat(builder, tmax_v)))
        mask = builder.zext(builder.bitcast(hit, ir.IntType(4)), i64)
        lanes = [builder.extract_element(t_near, ir.Constant(ir.IntType(32), k)) for k in range(4)]
        return context.make_tuple(builder, signature.return_type, [mask] + lanes)

    return sig, codegen

