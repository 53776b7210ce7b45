/* Structs shared byte for byte by the host (C++) and the kernels (OpenCL C).
 * Rules: only 4-byte scalars, fixed arrays of them and 16-byte vectors;
 * 16-byte members first; explicit padding; every size written down and checked on both sides
 * (static_assert on the host, tests/layout_test.cpp on the device). */
#ifndef PATHCL_SHARED_TYPES_H
#define PATHCL_SHARED_TYPES_H

#ifdef __OPENCL_VERSION__
typedef float4 pc_float4;
typedef uint pc_uint;
#else
#include <cstddef>
#include <cstdint>
struct alignas(16) pc_float4 {
  float x, y, z, w;
};
typedef uint32_t pc_uint;
#endif

#define PC_INVALID 0xffffffffu

/* The path integrator over W > 1 lanes (PC_LANES, kernels/lanes.cl): a work item renders W x
 * PC_LANE_PIXELS pixels of a unit, each lane taking the item's next pixel when it has done one. */
#define PC_LANE_PIXELS 16u

/* Primitive kinds (PrimShading.kind). */
#define PC_PRIM_TRIANGLE 0u
#define PC_PRIM_SPHERE 1u

/* Material types (Material.type). */
#define PC_MAT_DIFFUSE 0u
#define PC_MAT_OREN_NAYAR 1u
#define PC_MAT_PHONG 2u
#define PC_MAT_MIRROR 3u
#define PC_MAT_DIELECTRIC 4u
#define PC_MAT_ROUGH_CONDUCTOR 5u
#define PC_MAT_PLASTIC 6u
#define PC_MAT_THIN_DIELECTRIC 7u /* compiled with PC_HAS_DIELECTRIC */

/* Light types (Light.type). */
#define PC_LIGHT_AREA 0u
#define PC_LIGHT_POINT 1u
#define PC_LIGHT_SPOT 2u
#define PC_LIGHT_DIRECTIONAL 3u
#define PC_LIGHT_ENVIRONMENT 4u

/* An environment map's parameterisation, held in its Light's slot (an environment has no primitive):
 * a lat-long image (PC_INVALID, every other light's slot outside the area lights), or pbrt-v4's
 * equal-area octahedral square looked up bilinearly or at the nearest texel (kernels/environment.cl). */
#define PC_ENV_LAT_LONG PC_INVALID
#define PC_ENV_EQUAL_AREA 1u
#define PC_ENV_EQUAL_AREA_NEAREST 2u

/* Pixel filters (SceneHeader.filter), sampled by filter importance sampling. */
#define PC_FILTER_BOX 0u
#define PC_FILTER_TENT 1u
#define PC_FILTER_GAUSSIAN 2u

/* Texture wrap modes (Texture.wrap). */
#define PC_WRAP_REPEAT 0u
#define PC_WRAP_CLAMP 1u
#define PC_WRAP_MIRROR 2u

/* Samplers (SceneHeader.sampler): a per-render setting, chosen at run time. */
#define PC_SAMPLER_INDEPENDENT 0u
#define PC_SAMPLER_STRATIFIED 1u
#define PC_SAMPLER_SOBOL 2u
#define PC_SAMPLER_HALTON 3u

/* PrimShading.flags */
#define PC_FLAG_TWO_SIDED 1u   /* emits from both sides */
#define PC_FLAG_FLIP_NORMAL 2u /* sphere: normal points to the centre */
#define PC_FLAG_SMOOTH 4u      /* shading normals in the normals array */
#define PC_FLAG_VERTEX_COLORS 8u /* corner colours in the colors array */

/* The device's BVH, in the layout chosen for the device (runtime/device.h, bvh_width): 4-wide (GPUs),
 * 8-wide or 16-wide (CPUs), collapsed from the host's binary SAH tree (scene/bvh_build.h), flattened
 * depth-first. All layouts have the binary tree's leaves and primitive order, and a hit is the nearest by (t, primitive
 * index), so every layout gives the same hit records (kernels/intersect.cl). 4-wide: Child boxes are stored by coordinate so one float4 slab test checks all four:
 * lo_x, lo_y, lo_z, hi_x, hi_y, hi_z (6 x 16) + child (16) = 112 bytes.
 * child[i] is an interior node index, or a leaf reference (PC_BVH4_LEAF set) of primitives
 * [first, first + count): PC_LEAF_REF(first, count).
 * An unused child slot has an empty box (lo = +inf, hi = -inf) that every slab test misses. */
#define PC_BVH4_LEAF 0x80000000u
/* A leaf reference of primitives [first, first + count), count 1 to 16, and its two parts. */
#define PC_LEAF_REF(first, count) (PC_BVH4_LEAF | (first) << 4 | ((count) - 1u))
#define PC_LEAF_FIRST(ref) (((ref) & ~PC_BVH4_LEAF) >> 4)
#define PC_LEAF_COUNT(ref) (((ref) & 15u) + 1u)
#define PC_BVH4_MAX_LEAF_FIRST (1u << 27)
typedef struct {
  pc_float4 lo_x, lo_y, lo_z;
  pc_float4 hi_x, hi_y, hi_z;
  pc_uint child[4];
} Bvh4Node;

/* 8-wide (one float8 slab test checks all eight children): child (32) + lo_x .. hi_z (6 x 32) + pad (32) =
 * 256 bytes, four whole cache lines. The child references share the first line with lo_x, which every
 * node test loads, so they arrive with the planes instead of after the hit mask asks for them. Unused
 * slots as in Bvh4Node. Nodes and their leaves live in one array, bvh8 (PC_SCENE_ARRAYS), each node (at a
 * multiple of 64 bytes) followed by the LeafBlocks of its leaf children, as Embree's allocator lays them
 * out. References count 8-byte words from bvh8's start, so that an address is one scaled addition: an
 * interior child is its node's offset, a leaf (PC_BVH4_LEAF set) its first block's, and a leaf's blocks
 * follow each other up to the one marked last. Its leaves are binary subtrees of at most 16 primitives (or
 * a binary leaf). Against separate arrays of nodes and blocks addressed by index: bounce rays on the
 * benchmark terrain +3 %, camera rays +2 % (docs/benchmarks-notes.md). */
#define PC_BVH8_MAX_WORDS PC_BVH4_LEAF /* references below PC_BVH4_LEAF: 16 GiB */
typedef struct {
  pc_uint child[8];
  float lo_x[8], lo_y[8], lo_z[8];
  float hi_x[8], hi_y[8], hi_z[8];
  pc_uint pad[8]; /* zero */
} Bvh8Node;

/* 16-wide (CPUs with AVX-512: one float16 slab test checks all sixteen children, as fast there as float8):
 * child (64) + lo_x .. hi_z (6 x 64) = 448 bytes, seven whole cache lines, laid out in bvh16 and referenced
 * as Bvh8Node is in bvh8 (the same LeafBlocks after each node). A tree of two thirds the 8-wide one's
 * depth: a bounce ray on the benchmark terrain visits 7.0 nodes instead of 9.4, and is traced 14 % faster
 * (docs/benchmarks-notes.md). */
typedef struct {
  pc_uint child[16];
  float lo_x[16], lo_y[16], lo_z[16];
  float hi_x[16], hi_y[16], hi_z[16];
} Bvh16Node;

/* Up to four primitives of an 8- or 16-wide BVH leaf (in bvh8 or bvh16, after its parent node), vertices by coordinate, so
 * that one float4 watertight test checks four triangles: a, b, c by coordinate (9 x 16) + prim (16) +
 * first_slot, count, sphere_mask, last (16) = 176 bytes. Lane i is prims[first_slot + i]; a sphere's lane
 * is tested alone. */
typedef struct {
  pc_float4 ax, ay, az, bx, by, bz, cx, cy, cz;
  pc_uint prim[4];     /* scene-order primitive index of each lane */
  pc_uint first_slot;
  pc_uint count;       /* lanes in use, 1 to 4 */
  pc_uint sphere_mask; /* bit i: lane i is a sphere */
  pc_uint last;        /* 1 on a leaf's last block, else 0 */
} LeafBlock;

/* A node of a binary BVH flattened depth-first: lo (12) + left_first (4) + hi (12) + prim_count (4) = 32
 * bytes. Interior node (prim_count == 0): the left child is the next node, the right child is left_first.
 * Leaf: items [left_first, left_first + prim_count). The empty tree's root has neither. The host builds every BVH this way (scene/bvh_build.h); the device
 * gets it only as the instance BVH (instance_bvh: items are instances), the others collapsed to wide nodes. */
typedef struct {
  float lo[3];
  pc_uint left_first;
  float hi[3];
  pc_uint prim_count;
} BvhNode;

/* A placement of a mesh (PC_HAS_INSTANCES): the mesh's own BVH (its root in nodes, bvh8 and bvh16, over its
 * primitives, which are stored once in the mesh's coordinates) and the affine transforms between the
 * mesh's and the device's coordinates as three rows (x, y, z, translation) each. Instance 0 is the rest of
 * the scene, stored in device coordinates (PC_INSTANCE_IDENTITY: no transform is applied).
 * to_device (3 x 16) + to_mesh (3 x 16) + root4 (4) + root8 (4) + root16 (4) + flags (4) = 112 bytes. */
#define PC_INSTANCE_IDENTITY 1u
typedef struct {
  pc_float4 to_device[3];
  pc_float4 to_mesh[3];
  pc_uint root4; /* the mesh's root node in nodes (4-wide layout) */
  pc_uint root8; /* the root's offset in bvh8, in 8-byte words (8-wide layout) */
  pc_uint root16; /* the root's offset in bvh16, in 8-byte words (16-wide layout) */
  pc_uint flags; /* PC_INSTANCE_* */
} Instance;

/* Geometry in BVH leaf order: 3 x 16 = 48 bytes.
 * Triangle: a, b, c are the vertices. Sphere: a.xyz is the centre, b.x the radius.
 * a.w holds the primitive index (bits of a uint) in scene order, b.w the kind (bits of a uint). */
typedef struct {
  pc_float4 a;
  pc_float4 b;
  pc_float4 c;
} Primitive;

/* Per-primitive shading data, indexed by scene-order primitive index: 4 x 4 = 16 bytes. */
typedef struct {
  pc_uint material; /* index into materials */
  pc_uint light;    /* index into lights, or PC_INVALID */
  pc_uint flags;    /* PC_FLAG_* */
  pc_uint kind;     /* PC_PRIM_* */
} PrimShading;

/* A material; which fields mean something depends on the type:
 *   color:    diffuse, oren_nayar: reflectance; phong, plastic: diffuse colour; mirror: reflectance;
 *             dielectric: transmittance
 *   specular: phong: specular colour; rough_conductor: eta per channel
 *   k:        rough_conductor: absorption k per channel
 *   alpha:    rough_conductor, plastic: GGX alpha (roughness squared; 0 = smooth plastic coat)
 *   sigma:    oren_nayar: standard deviation of facet angles in radians
 *   exponent: phong: cosine lobe exponent
 *   ior:      dielectric, plastic: index of refraction inside over outside
 * color (16) + specular (16) + k (16) + type (4) + color_texture (4) + alpha (4) + sigma (4) + exponent (4)
 *   opacity:  cut-outs (PC_HAS_CUTOUTS): the fraction of rays the surface stops, 1 = opaque; with
 *             opacity_texture, times that texture's opacity (kernels/cutout.cl)
 * + ior (4) + opacity (4) + opacity_texture (4) = 80 bytes. */
typedef struct {
  pc_float4 color;
  pc_float4 specular;
  pc_float4 k;
  pc_uint type;
  pc_uint color_texture; /* index into textures replacing color, or PC_INVALID */
  float alpha;
  float sigma;
  float exponent;
  float ior;
  float opacity;
  pc_uint opacity_texture; /* index into textures, or PC_INVALID */
} Material;

/* A light. emission is the radiance of an area light, the intensity of a point or spot light, the
 * irradiance of a directional light (on a surface facing it) and the radiance (or the scale of the map)
 * of an environment light. Lights [0, SceneHeader.tree_light_count) (area, point, spot) are chosen through
 * the light BVH from the shading point; the rest (directional, environment) are the lights at infinity
 * (kernels/light_tree.cl).
 * emission (16) + position (16) + direction (16) + type (4) + prim (4) + slot (4) + area (4)
 * + infinite_share (4) + cos_inner (4) + cos_outer (4) + texture (4) + tree_leaf (4) + group_share (4)
 * + group_cdf (4) + pad (4) = 96 bytes. */
typedef struct {
  pc_float4 emission;
  pc_float4 position;  /* point, spot */
  pc_float4 direction; /* spot: cone axis; directional: the direction light travels in; unit length */
  pc_uint type;        /* PC_LIGHT_* */
  pc_uint prim;        /* area: scene-order primitive index */
  pc_uint slot;        /* area: the same primitive's index in the leaf-ordered primitive array;
                        * environment: its map's PC_ENV_*; others PC_INVALID */
  float area;          /* area: surface area */
  float infinite_share; /* lights at infinity: the probability of choosing this one among them; others 0 */
  float cos_inner;     /* spot: full intensity inside this cone */
  float cos_outer;     /* spot: none outside this cone */
  pc_uint texture;     /* environment: lat-long map in textures, or PC_INVALID for a constant */
  pc_uint tree_leaf;   /* lights in the light BVH: the index of its leaf in light_bvh; others PC_INVALID */
  float group_share;   /* lights in the light BVH: the probability of choosing it among its leaf's lights (its
                        * area over theirs: scene/light_bvh_build.h's emitter groups); 1 alone; others 0 */
  float group_cdf;     /* the shares of its leaf's lights up to it and with it (the last: exactly 1); others 0 */
  pc_uint pad;
} Light;

/* A node of the light BVH (scene/light_bvh_build.h), flattened depth-first: an interior node's first child
 * follows it, its second is at `second`, so a leaf's index tells at every node which way leads to it.
 * The bounds are those of pbrt-v4's LightBounds: a box, the peak radiant intensity, and a cone of emission
 * axes (half-angle theta_o) that every light of the node emits within theta_e of.
 * lo (16) + hi (16) + axis (16) + second (4) + light (4) + two_sided (4) + light_count (4) = 64 bytes. */
typedef struct {
  pc_float4 lo;      /* xyz: the box's lower corner; w: summed peak radiant intensity (luminance, W/sr) */
  pc_float4 hi;      /* xyz: the box's upper corner; w: cos theta_o */
  pc_float4 axis;    /* xyz: the cone's axis (unit length); w: cos theta_e */
  pc_uint second;    /* interior: index of the second child; leaf: PC_INVALID */
  pc_uint light;       /* leaf: index into lights of its first light; interior: PC_INVALID */
  pc_uint two_sided;   /* 1: the lights emit on both sides of their axes too */
  pc_uint light_count; /* leaf: its lights are [light, light + light_count) (1, or an emitter group); interior: 0 */
} LightBvhNode;

/* How a texture's texels are stored in the texel words (Texture.format), at the precision of the file:
 *   SRGB8: 4 bytes a texel, R G B A in byte order, 8-bit sRGB (decoded by kernels/shared/srgb_table.h)
 *   HALF:  6 bytes a texel, linear R G B as IEEE half floats (OpenEXR HALF channels)
 *   FLOAT: 12 bytes a texel, linear R G B as floats (OpenEXR FLOAT channels, Radiance HDR) */
#define PC_TEXELS_SRGB8 0u
#define PC_TEXELS_HALF 1u
#define PC_TEXELS_FLOAT 2u
/* Opacity maps (Material.opacity_texture) of 8-bit images: the linear value of byte 0 (red: a grey map)
 * or byte 3 (alpha) of an SRGB8 image's texels, in every channel. Half and float images are read as they
 * are, red for opacity. */
#define PC_TEXELS_OPACITY8_RED 3u
#define PC_TEXELS_OPACITY8_ALPHA 4u
/* A checkerboard (Mitsuba's), evaluated at the point: 10 words of floats, color0 (R G B), color1 (R G B),
 * tiles (u, v: tiles per unit of uv) and offset (u, v, in tiles); width 2 and height 1, so that the host's
 * texel loops see the two colours as a 2 x 1 FLOAT image (kernels/texture.cl, checker_lookup). */
#define PC_TEXELS_CHECKER 5u

/* An image in the texel words, rows top to bottom; each image starts at a word.
 * width (4) + height (4) + offset (4) + wrap (4) + format (4) + pad (12) = 32 bytes. */
typedef struct {
  pc_uint width;
  pc_uint height;
  pc_uint offset; /* index of the image's first word in texels */
  pc_uint wrap;   /* PC_WRAP_* */
  pc_uint format; /* PC_TEXELS_* */
  pc_uint pad[3];
} Texture;

/* Everything a render pass needs besides the arrays: 4 x 16 + 20 x 4 = 144 bytes. */
typedef struct {
  pc_float4 cam_position;
  pc_float4 cam_right;   /* image right, scaled by tan(fov_y / 2) * aspect */
  pc_float4 cam_up;      /* image up, scaled by tan(fov_y / 2) */
  pc_float4 cam_forward;
  pc_uint width;
  pc_uint height;
  pc_uint prim_count;
  pc_uint light_count;
  pc_uint max_depth;
  pc_uint seed;
  pc_uint rr_depth;      /* Russian roulette starts after this many scattering events */
  pc_uint node_count;
  pc_uint sampler;       /* PC_SAMPLER_* */
  pc_uint spp;           /* samples per pixel of the whole render (the stratified sampler's grid) */
  float lens_radius;     /* thin lens aperture radius; 0 = pinhole */
  float focus_distance;  /* distance along cam_forward of the plane in focus */
  pc_uint filter;        /* PC_FILTER_* */
  float filter_radius;   /* in pixels: tent half-width, or the Gaussian's cut-off (box: 0.5) */
  float filter_sigma;    /* Gaussian standard deviation in pixels */
  pc_uint env_light;     /* index of the environment light in lights, or PC_INVALID */
  pc_uint tree_light_count; /* lights [0, tree_light_count) are in light_bvh; the rest are at infinity */
  float infinite_irradiance; /* the lights at infinity's irradiance estimate (luminance), weighed against
                                the light BVH's from each shading point (kernels/light_tree.cl) */
  pc_uint pad[2];
} SceneHeader;

/* Statistics of one work unit, added up by its work items with integer atomics (in any order to the same
 * totals): rays_lo (4) + rays_hi (4) (the 64-bit ray count) + nan (4) + inf (4) + negative (4) + pad (12)
 * = 32 bytes. */
typedef struct {
  pc_uint rays_lo;
  pc_uint rays_hi;
  pc_uint nan_samples;
  pc_uint inf_samples;
  pc_uint negative_samples;
  pc_uint pad[3];
} UnitStats;

/* Ray file record (pathcl rays): origin (12) + tmin (4) + direction (12) + tmax (4) = 32 bytes. */
typedef struct {
  float org[3];
  float tmin;
  float dir[3];
  float tmax;
} RayRecord;

/* Hit file record: t (4, +inf for a miss) + prim (4, PC_INVALID for a miss) + u (4) + v (4) = 16 bytes. */
typedef struct {
  float t;
  pc_uint prim;
  float u;
  float v;
} HitRecord;

/* Every scene array the render kernels read, as X(element type, name), in kernel-argument order after the
 * SceneHeader. Everything that lists the arrays expands this one list: the kernels' parameters and
 * SceneData (kernels/scene.cl), DeviceScene's vectors (scene/device_scene.h), their upload and binding
 * (runtime/scene_buffers.h) and the checkpoint key (runtime/checkpoint.cpp). A new array is one line here. */
#define PC_SCENE_ARRAYS(X)                                                                              \
  X(Bvh4Node, nodes) X(pc_float4, bvh8) X(pc_float4, bvh16) X(Primitive, prims) X(PrimShading, shading)  \
  X(pc_float4, normals) X(pc_float4, uvs) X(pc_float4, colors) X(Material, materials) X(Light, lights) X(float, light_cdf) X(LightBvhNode, light_bvh)          \
  X(Texture, textures) X(pc_uint, texels)                                                                      \
  X(float, env_dist) X(Instance, instances) X(BvhNode, instance_bvh)

/* X-macro of every shared struct and field; the layout test compares sizeof and offsetof on both sides. */
#define PC_LAYOUT_STRUCTS(X) \
  X(BvhNode) X(Instance) X(Bvh4Node) X(Bvh8Node) X(Bvh16Node) X(LeafBlock) X(Primitive) X(PrimShading) X(Material) X(Light) X(LightBvhNode) X(Texture) X(SceneHeader) X(UnitStats) X(RayRecord) X(HitRecord)
#define PC_LAYOUT_FIELDS(X)                                                                                \
  X(BvhNode, lo) X(BvhNode, left_first) X(BvhNode, hi) X(BvhNode, prim_count) X(Instance, to_device) X(Instance, to_mesh) \
  X(Instance, root4) X(Instance, root8) X(Instance, root16) X(Instance, flags) \
  X(Bvh4Node, lo_x) X(Bvh4Node, lo_y) X(Bvh4Node, lo_z) \
  X(Bvh4Node, hi_x) X(Bvh4Node, hi_y) X(Bvh4Node, hi_z) X(Bvh4Node, child) X(Bvh8Node, lo_x) X(Bvh8Node, lo_y) \
  X(Bvh8Node, lo_z) X(Bvh8Node, hi_x) X(Bvh8Node, hi_y) X(Bvh8Node, hi_z) X(Bvh8Node, child) X(Bvh16Node, lo_x) \
  X(Bvh16Node, lo_y) X(Bvh16Node, lo_z) X(Bvh16Node, hi_x) X(Bvh16Node, hi_y) X(Bvh16Node, hi_z) X(Bvh16Node, child) X(LeafBlock, ax) \
  X(LeafBlock, cz) X(LeafBlock, prim) X(LeafBlock, first_slot) X(LeafBlock, count) X(LeafBlock, sphere_mask) X(LeafBlock, last) X(Primitive, a)                \
  X(Primitive, b) X(Primitive, c) X(PrimShading, material) X(PrimShading, light) X(PrimShading, flags)      \
  X(PrimShading, kind) X(Material, color) X(Material, specular) X(Material, k) X(Material, type)             \
  X(Material, color_texture) X(Material, alpha) X(Material, sigma) X(Material, exponent) X(Material, ior) X(Material, opacity) X(Material, opacity_texture)  \
  X(Light, emission) X(Light, position) X(Light, direction) X(Light, type) X(Light, prim) X(Light, slot)    \
  X(Light, area) X(Light, infinite_share) X(Light, cos_inner) X(Light, cos_outer) X(Light, texture) X(Light, tree_leaf) X(Light, group_share) X(Light, group_cdf) \
  X(LightBvhNode, lo) X(LightBvhNode, hi) X(LightBvhNode, axis) X(LightBvhNode, second) X(LightBvhNode, light) X(LightBvhNode, two_sided) X(LightBvhNode, light_count)           \
  X(Texture, width) X(Texture, height) X(Texture, offset) X(Texture, wrap) X(Texture, format) X(SceneHeader, cam_position) X(SceneHeader, cam_right)               \
  X(SceneHeader, cam_up) X(SceneHeader, cam_forward) X(SceneHeader, width) X(SceneHeader, height)          \
  X(SceneHeader, prim_count) X(SceneHeader, light_count) X(SceneHeader, max_depth) X(SceneHeader, seed)    \
  X(SceneHeader, rr_depth) X(SceneHeader, node_count) X(SceneHeader, sampler) X(SceneHeader, spp) X(SceneHeader, lens_radius) X(SceneHeader, focus_distance) X(SceneHeader, filter)  \
  X(SceneHeader, filter_radius) X(SceneHeader, filter_sigma) X(SceneHeader, env_light) X(SceneHeader, tree_light_count) X(SceneHeader, infinite_irradiance) X(UnitStats, rays_lo) X(UnitStats, rays_hi) X(UnitStats, nan_samples)         \
  X(UnitStats, inf_samples) X(UnitStats, negative_samples) X(RayRecord, org) X(RayRecord, tmin)            \
  X(RayRecord, dir) X(RayRecord, tmax) X(HitRecord, t) X(HitRecord, prim) X(HitRecord, u) X(HitRecord, v)

#ifndef __OPENCL_VERSION__
static_assert(sizeof(BvhNode) == 32, "BvhNode is 32 bytes");
static_assert(sizeof(Instance) == 112, "Instance is 112 bytes");
static_assert(sizeof(Bvh4Node) == 112, "Bvh4Node is 112 bytes");
static_assert(sizeof(Bvh8Node) == 256, "Bvh8Node is 256 bytes");
// kernels/intersect.cl (fused_slabs) loads a node's planes from these float offsets.
static_assert(offsetof(Bvh8Node, lo_y) - offsetof(Bvh8Node, lo_x) == 8 * sizeof(float) &&
                  offsetof(Bvh8Node, lo_z) - offsetof(Bvh8Node, lo_x) == 16 * sizeof(float) &&
                  offsetof(Bvh8Node, hi_x) - offsetof(Bvh8Node, lo_x) == 24 * sizeof(float) &&
                  offsetof(Bvh8Node, hi_y) - offsetof(Bvh8Node, lo_x) == 32 * sizeof(float) &&
                  offsetof(Bvh8Node, hi_z) - offsetof(Bvh8Node, lo_x) == 40 * sizeof(float),
              "Bvh8Node's planes are eight floats apart, lo_x .. hi_z");
static_assert(sizeof(Bvh16Node) == 448, "Bvh16Node is 448 bytes");
static_assert(offsetof(Bvh16Node, lo_y) - offsetof(Bvh16Node, lo_x) == 16 * sizeof(float) &&
                  offsetof(Bvh16Node, lo_z) - offsetof(Bvh16Node, lo_x) == 32 * sizeof(float) &&
                  offsetof(Bvh16Node, hi_x) - offsetof(Bvh16Node, lo_x) == 48 * sizeof(float) &&
                  offsetof(Bvh16Node, hi_y) - offsetof(Bvh16Node, lo_x) == 64 * sizeof(float) &&
                  offsetof(Bvh16Node, hi_z) - offsetof(Bvh16Node, lo_x) == 80 * sizeof(float),
              "Bvh16Node's planes are sixteen floats apart, lo_x .. hi_z");
static_assert(sizeof(LeafBlock) == 176, "LeafBlock is 176 bytes");
static_assert(sizeof(Primitive) == 48, "Primitive is 48 bytes");
static_assert(sizeof(PrimShading) == 16, "PrimShading is 16 bytes");
static_assert(sizeof(Material) == 80, "Material is 80 bytes");
static_assert(sizeof(Light) == 96, "Light is 96 bytes");
static_assert(sizeof(LightBvhNode) == 64, "LightBvhNode is 64 bytes");
static_assert(sizeof(Texture) == 32, "Texture is 32 bytes");
static_assert(sizeof(SceneHeader) == 144, "SceneHeader is 144 bytes");
static_assert(sizeof(UnitStats) == 32, "UnitStats is 32 bytes");
static_assert(sizeof(RayRecord) == 32, "RayRecord is 32 bytes");
static_assert(sizeof(HitRecord) == 16, "HitRecord is 16 bytes");
#endif

#endif
