"""The flat arrays the kernels see (`SceneArrays`), and the meaning of their columns.

Built once by `lumos.compile.compile_scene`; every array is contiguous. Triangles and bounded analytic shapes
share one BVH; its leaves index `prim_ref`, whose entries are a triangle index (>= 0) or the bitwise complement
of a shape index (< 0). Unbounded shapes (planes) are tested outside the BVH.
"""

from collections import namedtuple

# Shape kinds: canonical object-space shapes; `shape_xform` maps world points into object space.
SHAPE_SPHERE = 0  # unit sphere at the origin
SHAPE_BOX = 1  # the cube [0, 1]^3
SHAPE_CYLINDER = 2  # x^2 + y^2 = 1, 0 <= z <= 1 (caps at z = 0 and z = 1 when capped)
SHAPE_CONE = 3  # x^2 + y^2 = (1 - z)^2, 0 <= z <= 1, apex at z = 1 (cap at z = 0 when capped)
SHAPE_DISK = 4  # x^2 + y^2 <= 1 in the plane z = 0, normal +z
SHAPE_RECT = 5  # [0, 1]^2 in the plane z = 0, normal +z (area lights)
SHAPE_PLANE = 6  # the plane z = 0, normal +z (unbounded)
SHAPE_CSG = 7  # a csg object: INFO_REF is its root node in csg_nodes (see kernels.csg)
SHAPE_MESH_SOLID = 8  # a closed mesh inside a csg object: triangles INFO_REF .. INFO_REF + INFO_COUNT - 1

# shape_info / tri_info columns
INFO_KIND = 0  # shapes only
INFO_MATERIAL = 1
INFO_OBJECT = 2
INFO_FLAGS = 3
INFO_LIGHT = 4  # area light index for emitter geometry, else -1
INFO_REF = 5  # shapes: csg root node (SHAPE_CSG) or first triangle (SHAPE_MESH_SOLID)
INFO_COUNT = 6  # shapes: number of solids (SHAPE_CSG) or of triangles (SHAPE_MESH_SOLID)
SHAPE_INFO_SIZE = 7

FLAG_CAPPED = 1  # shapes: cylinder/cone caps
FLAG_READS_UV = 2  # shapes: the material reads (u, v) (a texture or bump map); the others skip computing them
FLAG_NORMALS = 1  # triangles: per-vertex shading normals present
FLAG_UVS = 2  # triangles: per-vertex uvs present
FLAG_TANGENTS = 4  # triangles: per-vertex tangents present (in tri_tangents)

# Material columns (materials: float64 (n, MAT_SIZE))
MAT_KA = 0
MAT_KD = 3
MAT_KS = 6
MAT_SHININESS = 9
MAT_KR = 10
MAT_KT = 13
MAT_IOR = 16
MAT_EMISSION = 17
MAT_FRESNEL = 20  # 1.0: Schlick-weighted reflection and transmission (whitted)
MAT_TEXTURE = 21  # first row in tex_info of the material's textures, or -1 (they follow one another)
MAT_BUMP = 22  # row in tex_info of its bump map, or -1
MAT_TEXTURE_COUNT = 23  # how many tex_info rows from MAT_TEXTURE are its textures (0 with none)
MAT_CUTOUT = 24  # 1.0: one of its textures applies to opacity, so its surfaces may have holes (kernels.cutout)
MAT_ONE_SIDED = 25  # 1.0: its emission leaves the front only (the side the geometric normal faces); it reflects on both
# The physical model the path tracer reads (the columns above are the classic model's, which the local methods
# read; for a conductor the compile step derives them from these): MODEL_CLASSIC, MODEL_CONDUCTOR, ...
MAT_MODEL = 26
MAT_ALPHA = 27  # GGX widths (αu, αv) along the tangent frame's two axes (`kernels.microfacet`)
MAT_ETA = 29  # conductor: the real part of the complex index of refraction, per channel (0: a perfect reflector);
# plastic: MAT_ETA alone, the coat's index (inside over outside); dielectric: MAT_ETA alone, int_ior / ext_ior
MAT_K = 32  # conductor: its imaginary part (extinction), per channel
MAT_TINT_T = 32  # dielectric (no k): a factor on the transmitted light per channel (Mitsuba's specular_transmittance)
MAT_TINT = 35  # conductor, plastic, dielectric: a factor on the lobe's reflectance per channel (Mitsuba's
# specular_reflectance)
MAT_FDR = 38  # plastic: the coat's internal diffuse reflectance (light from the base sent back down to it)
# plastic: MAT_COAT_SIZE values of t(cos θ) = 1 − the coat's directional reflectance, at cos θ = i/(size − 1)
MAT_COAT = 39
MAT_COAT_SIZE = 64
MAT_SIZE = MAT_COAT + MAT_COAT_SIZE
# principled (glTF's metallic–roughness, `kernels.principled`): its factors, which its textures multiply per hit
MAT_BASE = 29  # the base colour b per channel
MAT_METALLIC = 32  # m
MAT_ROUGHNESS = 33  # perceptual roughness r (GGX α = r², written into MAT_ALPHA per hit)
MAT_TRANSMISSION = 34  # t, the share of the dielectric's base that is smooth glass of index MAT_IOR
MAT_F0 = 35  # the dielectric's reflectance head-on per channel (from ior, specular, specular_color)
MAT_F90 = 38  # and at grazing incidence (KHR_materials_specular's factor)
MAT_CLEARCOAT = 39  # KHR_materials_clearcoat: the coat's factor c (0: none)
MAT_COAT_ALPHA = 40  # its GGX width (clearcoatRoughness²)
MAT_COAT_WEIGHT = 41  # per hit: c·Fc(n·wo), the share of the light the coat takes (Schlick, F0 0.04)
MAT_COAT_SHARE = 42  # per hit: the probability of sampling the coat's lobe rather than the base's glossy one
MAT_KA_REFLECTS = 43  # 1.0: its classic ka includes what it reflects (no environment lights the model)
# conductor, dielectric (columns the plastic's coat table holds in a plastic's row): per hit, the surface's ∂p/∂u,
# the direction αu lies along (`microfacet.tangent_frame`); (0, 0, 0) in the material's own row
MAT_TANGENT = 60

MODEL_CLASSIC = 0  # kd, ks/shininess, kr, kt read as kernels.bsdf says
MODEL_CONDUCTOR = 1  # a metal: GGX microfacets (a mirror when α = 0) with the Fresnel factor of η + ik
MODEL_PLASTIC = 2  # kd under a dielectric coat of index MAT_ETA: GGX microfacets (a mirror when α = 0)
MODEL_DIELECTRIC = 3  # glass of relative index MAT_ETA: GGX reflection and refraction (smooth glass when α = 0)
MODEL_PRINCIPLED = 4  # glTF's metallic–roughness: a metal and a dielectric over a Lambertian base, mixed by metallic

# The ambient light Ia (SceneArrays.ambient): a constant (row 0) plus, with an environment and no `ambient` given,
# its irradiance E(n)/π in the nine real spherical harmonics of bands 0-2 (Ramamoorthi & Hanrahan 2001: the
# clamped cosine keeps l <= 2 to within a few per cent)
AMBIENT_ROWS = 10
# With an environment that lights the local model, the ambient array goes on with its glossy reflection
# (`compile.environment.glossy_levels`, `environment.glossy_radiance`): row GLOSSY_HEADER = (level count K, cos and
# sin of the environment's rotation), then one row per level k = (its first texel row, width, height), then the
# texels: level k is the lat-long image convolved with the normalised Phong lobe of exponent GLOSSY_BASE^k about
# each texel's direction, `width` texels a row from its first row on.
GLOSSY_HEADER = AMBIENT_ROWS
GLOSSY_BASE = 4.0

# Light kinds and columns. Kinds up to LIGHT_DIRECTIONAL are delta lights (one direction per shading point, no
# random samples); the kinds above them are area lights.
LIGHT_POINT = 0
LIGHT_SPOT = 1  # a point light limited to a cone (see illumination.spot_falloff)
LIGHT_DIRECTIONAL = 2
LIGHT_RECT = 3
LIGHT_DISK = 4
LIGHT_SPHERE = 5

# light_vecs: float64 (n, 6, 3)
LV_POSITION = 0  # point/spot position; rect corner; disk/sphere centre
LV_DIRECTION = 1  # directional: unit direction of travel; spot: unit axis it shines along; rect/disk: unit normal
LV_EDGE_U = 2  # rect: edge_u; disk: radius * first tangent
LV_EDGE_V = 3  # rect: edge_v; disk: radius * second tangent
LV_DIFFUSE = 4  # Id (point/spot/directional) or radiance Le (area)
LV_SPECULAR = 5  # Is (point/spot/directional) or radiance Le (area)
# light_scalars: float64 (n, LS_SIZE)
LS_ATT_C = 0  # point/spot: attenuation [c, l, q]
LS_ATT_L = 1
LS_ATT_Q = 2
LS_RADIUS = 3  # disk/sphere
LS_AREA = 4  # area lights
LS_COS_OUTER = 5  # spot: cos(angle), no light where cosθ < it
LS_COS_INNER = 6  # spot: cos(inner_angle), full intensity where cosθ >= it
LS_TWO_SIDED = 7  # rect/disk: 1.0 when it emits on both sides (else along LV_DIRECTION only)
LS_SIZE = 8

# Emitters of the path tracer (`Emitters`): every light and every emissive primitive, picked by power
EMIT_LIGHT = 0  # a scene light (point, spot, directional or area; its light_kind says which); emit_ref: light index
EMIT_TRIANGLE = 1  # an emissive triangle, sampled uniformly by area; emit_ref: triangle index
EMIT_SHAPE = 2  # an emissive analytic shape, sampled by area (see kernels.emitters); emit_ref: shape index
EMIT_SPHERE = 3  # an emissive sphere of uniform scale, sampled in the cone it subtends; emit_ref: shape index
EMIT_ENV = 4  # the environment, sampled by its image's radiance (kernels.environment); emit_ref: 0
# Emitters.env_info columns (compile.environment)
ENV_PRESENT = 0  # 1.0 when the scene has an environment
ENV_COS = 1  # cos and sin of its rotation about +y
ENV_SIN = 2
ENV_WIDTH = 3
ENV_HEIGHT = 4
ENV_ENTRY = 5  # its entry in the emitter table (−1: none)
ENV_INFO_SIZE = 6
EMIT_PARTS = 6  # columns of emit_parts: one probability per part (face) of a shape
# The light tree (`kernels.light_tree`, built by `compile.light_tree`): Emitters.tree_nodes float64 columns, one
# pbrt LightBounds per node
TREE_MIN = 0  # bounding box min xyz
TREE_MAX = 3  # and max xyz
TREE_W = 6  # the unit axis of the cone bounding the emitters' normals
TREE_PHI = 9  # summed power (> 0)
TREE_COS_O = 10  # cos θo: the normal cone's half-angle (-1: every direction)
TREE_COS_E = 11  # cos θe: how far beyond its normal an emitter still emits (0: π/2, an area emitter)
TREE_TWO_SIDED = 12  # 1.0: one of them emits on both sides of its normal
TREE_SIZE = 13
# Emitters.tree_link int32 columns
TREE_FIRST = 0  # first child (the second is the next node), -1 for a leaf
TREE_ITEM = 1  # a leaf's emitter entry, else -1
TREE_PARENT = 2  # -1 for the root

# Camera: cam_vecs float64 (4, 3) = position, u, v, w; cam_params float64 (CAM_SIZE,)
CAM_ORTHO = 0  # 1.0 for orthographic
CAM_TAN_HALF_FOV = 1
CAM_HALF_SIZE = 2  # orthographic: half the vertical extent
CAM_APERTURE = 3
CAM_FOCUS = 4
CAM_FILTER = 5  # the pixel filter that places raycast's and whitted's supersamples: camera.FILTER_BOX or _GAUSSIAN
CAM_SIZE = 6

# BVH nodes: 32 bytes each (six float32 bounds, two int32 links) so that a pair of siblings fills one 64-byte
# cache line. Interior: NODE_FIRST = first child (its sibling follows), NODE_COUNT = 0. Leaf: NODE_FIRST = first
# entry in prim_ref, NODE_COUNT = number of primitives.
NODE_FIRST = 6
NODE_COUNT = 7

# The wide tree that traversal walks (built from the binary one, `compile.bvh.wide_nodes`): WIDE children per
# node, 32·WIDE bytes on 64-byte boundaries. Float32 columns 0 .. 6·WIDE-1: six bound rows (min x, y, z, max x,
# y, z) of the children's values each, as `kernels.simd.wide_box_test` loads them; int32 columns WIDE_CHILD..: each
# child's wide node index or first prim_ref entry; WIDE_COUNT..: its leaf primitive count (0: a wide node; -1: an
# empty slot). A traversal stack entry is a wide node index, or ~(WIDE·node + slot) for a leaf child.
WIDE = 8
WIDE_SHIFT = 3  # log2(WIDE)
WIDE_CHILD = 6 * WIDE
WIDE_COUNT = 7 * WIDE
WIDE_SIZE = 8 * WIDE  # columns per node
# A leaf of one to four triangles has a packed row (`compile.bvh.packed_leaves`) that `kernels.simd.tri4_test`
# tests at once: its wide slot holds count LEAF_PACKED and the row's index. Rows are 48 float32 (192 bytes) on
# 64-byte boundaries: columns 0-35 the triangles' coordinates as nine rows of four lanes (v0.x, v0.y, v0.z,
# v1.x, ..., v2.z), int32 column LEAF_BASE the first triangle's index (the others follow it), LEAF_MASK the
# mask of lanes that hold a triangle; then, per lane, what a ray query reports of a hit, so that its record is
# read from the row the hit test has just loaded: LEAF_OBJECT..+3 the triangle's object id (tri_info's), LEAF_FACE
# ..+3 its face index in its own mesh (-1 where it has none), and LEAF_UVS the mask of lanes with uvs.
LEAF_PACKED = -2
LEAF_BASE = 36
LEAF_MASK = 37
LEAF_OBJECT = 38
LEAF_FACE = 42
LEAF_UVS = 46

SceneArrays = namedtuple(
    "SceneArrays",
    [
        "tri_verts",  # float32 (nt, 9): world-space v0, v1, v2
        "tri_normals",  # float32 (nt, 9): per-vertex shading normals (zeros when absent)
        "tri_uvs",  # float32 (nt, 6): per-vertex uvs (zeros when absent)
        "tri_info",  # int32 (nt, 5): see INFO_*
        "shape_xform",  # float64 (ns, 4, 4): rows 0-2 object_from_world; row 3 the motion (velocity, world) and
        # in column 3 a 1.0 when the shape moves (its object space at time τ is object_from_world(p − τ·motion))
        "shape_info",  # int32 (ns, SHAPE_INFO_SIZE): see INFO_*
        "shape_nscale",  # float64 (ns, 3): 1/|row a of object_from_world's linear part|, which turns the world
        # normal of a canonical face whose normal is ±axis a (box faces, rects, disks, planes, caps) into a unit one
        "prim_ref",  # int32 (np,): BVH leaf order -> triangle (>= 0) or ~shape (< 0)
        "node_box",  # float32 (nn, 8): min xyz, max xyz in columns 0-5 (columns 6-7 hold the link bits)
        "node_link",  # int32 (nn, 8): an int32 view of node_box; columns NODE_FIRST, NODE_COUNT
        "wide_nodes",  # float32 (nw, WIDE_SIZE): the wide tree, see WIDE_*
        "wide_link",  # int32 (nw, WIDE_SIZE): an int32 view of wide_nodes
        "leaf_tris",  # float32 (nl, 48): packed triangle leaves, see LEAF_*
        "leaf_link",  # int32 (nl, 48): an int32 view of leaf_tris
        "unbounded",  # int32 (nu,): shapes tested outside the BVH
        "materials",  # float64 (nm, MAT_SIZE)
        "light_kind",  # int32 (nl,)
        "light_samples",  # int32 (nl,)
        "light_vecs",  # float64 (nl, 6, 3)
        "light_scalars",  # float64 (nl, LS_SIZE)
        "ambient",  # float64 (AMBIENT_ROWS, 3): Ia(n) = row 0 + Σ_k row k · Y_k(n), the rows 1-9 the irradiance over
        # π of the environment in real spherical harmonics up to l = 2 (`illumination.ambient_light`), then its
        # glossy reflection (GLOSSY_HEADER on); (1, 3), the constant alone, where no environment is read
        "background",  # float64 (3,)
        "env_pixels",  # float32 (H, W, 3): the environment's lat-long radiance (1×1 black without one)
        "env_info",  # float64 (ENV_INFO_SIZE,): present, rotation, size (compile.environment)
        "csg_nodes",  # int32 (nc, 4): see kernels.csg
        "tex_info",  # float64 (nx, TEX_SIZE): textures and bump maps, see kernels.texture
        "tex_pixels",  # float32 (npx, 3): every image texture's texels, row after row, one after another
        "tri_tangents",  # float32 (nt, 12): per-vertex tangents (xyz, w) of triangles with FLAG_TANGENTS; (0, 12)
        # when no triangle has them
    ],
)

# Views: small namedtuples over the same arrays, one per stage. Numba passes a namedtuple of arrays by value,
# every field of every member, at every call that is not inlined (`kernels.jit`); with all 17 arrays of
# SceneArrays that cost more than the work itself (measured: 150 ns per missed ray, against 40 ns with 7 arrays).
# Kernels build the views once per row or chunk (`kernels.views`) and hand each stage only its own.

#: What traversal needs (closest_hit, any_hit).
Geometry = namedtuple(
    "Geometry",
    ["node_box", "node_link", "prim_ref", "tri_verts", "shape_xform", "shape_info", "unbounded", "csg_nodes",
     "wide_nodes", "wide_link", "leaf_tris", "leaf_link"],
)
#: What turns a hit into a surface (surface_at).
Surfaces = namedtuple("Surfaces", ["tri_verts", "tri_normals", "tri_uvs", "tri_info", "shape_xform", "shape_info",
                                   "shape_nscale"])
#: What the illumination model reads (illuminate, sample_light); tex_info and tex_pixels for the opacity
#: cut-outs that shadow rays pass through (`kernels.cutout`: a Lighting view serves as the `tex` of
#: `texture.is_hole`).
Lighting = namedtuple(
    "Lighting", ["materials", "ambient", "light_kind", "light_samples", "light_vecs", "light_scalars", "tex_info",
                 "tex_pixels"]
)
#: What the path tracer's light sampling reads besides `Lighting` (built by `compile.emitters`).
Emitters = namedtuple(
    "Emitters",
    [
        "emit_kind",  # int32 (ne,): EMIT_*
        "emit_ref",  # int32 (ne,): light, triangle or shape index
        "emit_cdf",  # float64 (ne,): cumulative selection probability (last entry 1)
        "emit_pmf",  # float64 (ne,): selection probability, proportional to the emitter's power
        "emit_area",  # float64 (ne,): world area (triangles, shapes)
        "emit_slot",  # int32 (ne,): shapes: their row of emit_parts and emit_geom; -1 for lights and triangles
        "emit_parts",  # float64 (nsh, EMIT_PARTS): per shape, the probability of each part (face), by part id
        "emit_geom",  # float64 (nsh, 4, 4): per shape, rows 0-2 world_from_canonical and [3, 0] the |det| of
        # its linear part; spheres: [3, :] = centre, radius
        "tri_emit",  # int32 (nt,): entry of each triangle, -1 if it does not emit
        "shape_emit",  # int32 (ns,): entry of each shape, -1 if it is not sampled
        "light_emit",  # int32 (nl,): entry of each light
        "env_pixels",  # float32 (H, W, 3): the environment's lat-long radiance (1×1 black without one)
        "env_marginal",  # float64 (H + 1,): CDF over its rows (compile.environment)
        "env_conditional",  # float64 (H, W + 1): CDF over each row's pixels
        "env_info",  # float64 (ENV_INFO_SIZE,): present, cos and sin of its rotation, W, H, its entry
        # light selection (`kernels.emitters.select_emitter`): by the light tree where these are not both empty,
        # else by power (emit_cdf)
        "tree_nodes",  # float64 (nn, TREE_SIZE): the light tree's nodes, see TREE_*
        "tree_link",  # int32 (nn, 3): its links, see TREE_FIRST..
        "emit_node",  # int32 (ne,): each entry's leaf in the tree; -2: picked outside it; -1: never picked
        "emit_unbounded",  # int32 (nu,): the entries picked outside the tree (directional, environment...)
        "unbounded_cdf",  # float64 (nu,): cumulative probability of picking them (the last: all of them together)
    ],
)
#: Radiosity's patches (`compile.patches`), as the solvers' kernels read them (`kernels.radiosity`).
PatchArrays = namedtuple(
    "PatchArrays",
    [
        "corners",  # float64 (n, 4, 3): corners counter-clockwise about the patch's normal (row 3 unused for k=3)
        "k",  # int32 (n,): 3 or 4 corners
        "centre",  # float64 (n, 3)
        "normal",  # float64 (n, 3): unit, the way the patch faces
        "area",  # float64 (n,)
        "rho",  # float64 (n, 3): reflectance
        "emission",  # float64 (n, 3): Le
        "poly",  # int32 (n,): the polygon the patch is a side of (ray hits report polygons)
        "side_patch",  # int32 (npoly, 2): patch of each polygon's front and back side, -1 where none
        "poly_normal",  # float64 (npoly, 3): unit normal of each polygon's front side
    ],
)
#: The environment as a light to gather from (`kernels.environment`'s env_* functions read these fields of
#: `Emitters` or of this): radiosity's sky light (`kernels.radiosity.sky_light`).
EnvironmentTable = namedtuple("EnvironmentTable", ["env_pixels", "env_marginal", "env_conditional", "env_info"])
#: What texture lookups read (kernels.texture).
Textures = namedtuple("Textures", ["tex_info", "tex_pixels", "tri_tangents"])
