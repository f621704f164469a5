"""Numeric constants shared by the compile step and the kernels (one place for every epsilon)."""

#: Offset, relative to the scale of the hit point, used when spawning secondary rays off a surface.
RAY_EPSILON = 1e-4
#: A distance larger than any in a scene: "no hit yet". Finite on purpose (fastmath may fold np.inf away).
T_FAR = 1e30
#: BVH: leaf size at most, in triangles (an analytic shape counts as four: a leaf holds one), and SAH bins.
BVH_MAX_LEAF = 4
BVH_BINS = 16
#: SAH cost of one traversal step (two child-box tests) relative to one primitive test.
BVH_COST_TRAVERSAL = 1.0
#: BVH traversal stack depth: the wide walk pushes at most WIDE − 1 = 7 entries per level (`kernels.layout.WIDE`)
#: and the tree is at most `kernels.bvh_build.MAX_DEPTH` (60) levels deep, so 7·60 + 1 entries always suffice;
#: the closest-hit walk keeps a node's WIDE child entry distances in the top WIDE entries of its float stack.
BVH_STACK = 448
#: Largest image the film will allocate (pixels), and the default render size.
MAX_PIXELS = 16384 * 16384
DEFAULT_WIDTH = 640
DEFAULT_HEIGHT = 480
#: A spot light whose cos(inner_angle) − cos(angle) is below this has a hard edge: full light inside the cone
#: (cosθ >= cos angle), none outside, instead of the s² falloff between the two cones.
SPOT_HARD_EDGE = 1e-9
#: A ray passes through at most this many opacity cut-out holes (`kernels.cutout`); the next surface it meets
#: counts as opaque, hole or not (a bound on the work, never reached by real models).
MAX_HOLES = 64
