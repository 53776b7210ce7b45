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

/* Primitive kinds (PrimShading.kind). */
#define PC_PRIM_TRIANGLE 0u
#define PC_PRIM_SPHERE 1u

/* Material types (Material.type). */
#define PC_MAT_DIFFUSE 0u

/* Samplers (SceneHeader.sampler): a per-render setting, chosen at run time. */
#define PC_SAMPLER_INDEPENDENT 0u
#define PC_SAMPLER_STRATIFIED 1u
#define PC_SAMPLER_SOBOL 2u
#define PC_SAMPLER_HALTON 3u

/* PrimShading.flags */
#define PC_FLAG_TWO_SIDED 1u   /* emits from both sides */
#define PC_FLAG_FLIP_NORMAL 2u /* sphere: normal points to the centre */
#define PC_FLAG_SMOOTH 4u      /* shading normals in the normals array */

/* One BVH node, flattened depth-first: lo (12) + left_first (4) + hi (12) + prim_count (4) = 32 bytes.
 * Interior node (prim_count == 0): the left child is the next node, the right child is left_first.
 * Leaf: primitives [left_first, left_first + prim_count) of the primitive array. */
typedef struct {
  float lo[3];
  pc_uint left_first;
  float hi[3];
  pc_uint prim_count;
} BvhNode;

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

/* reflectance (16) + type (4) + pad (12) = 32 bytes. */
typedef struct {
  pc_float4 reflectance;
  pc_uint type;
  pc_uint pad[3];
} Material;

/* An area light: one emitting triangle or sphere.
 * emission (16) + prim (4) + slot (4) + area (4) + select_pdf (4) = 32 bytes. */
typedef struct {
  pc_float4 emission;
  pc_uint prim;      /* scene-order primitive index */
  pc_uint slot;      /* the same primitive's index in the leaf-ordered primitive array */
  float area;
  float select_pdf;  /* probability of choosing this light, proportional to power */
} Light;

/* Everything a render pass needs besides the arrays: 4 x 16 + 12 x 4 = 112 bytes. */
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
  pc_uint pad[2];
} SceneHeader;

/* Statistics one work item writes per pass (not accumulated, so any split gives the same totals):
 * rays (4) + nan (4) + inf (4) + negative (4) = 16 bytes. */
typedef struct {
  pc_uint rays;
  pc_uint nan_samples;
  pc_uint inf_samples;
  pc_uint negative_samples;
} PassStats;

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

/* X-macro of every shared struct and field; the layout test compares sizeof and offsetof on both sides. */
#define PC_LAYOUT_STRUCTS(X) \
  X(BvhNode) X(Primitive) X(PrimShading) X(Material) X(Light) X(SceneHeader) X(PassStats) X(RayRecord) X(HitRecord)
#define PC_LAYOUT_FIELDS(X)                                                                                \
  X(BvhNode, lo) X(BvhNode, left_first) X(BvhNode, hi) X(BvhNode, prim_count) X(Primitive, a)                \
  X(Primitive, b) X(Primitive, c) X(PrimShading, material) X(PrimShading, light) X(PrimShading, flags)      \
  X(PrimShading, kind) X(Material, reflectance) X(Material, type) X(Light, emission) X(Light, prim)          \
  X(Light, slot) X(Light, area) X(Light, select_pdf) X(SceneHeader, cam_position) X(SceneHeader, cam_right)               \
  X(SceneHeader, cam_up) X(SceneHeader, cam_forward) X(SceneHeader, width) X(SceneHeader, height)          \
  X(SceneHeader, prim_count) X(SceneHeader, light_count) X(SceneHeader, max_depth) X(SceneHeader, seed)    \
  X(SceneHeader, rr_depth) X(SceneHeader, node_count) X(SceneHeader, sampler) X(SceneHeader, spp) X(PassStats, rays) X(PassStats, nan_samples)         \
  X(PassStats, inf_samples) X(PassStats, negative_samples) X(RayRecord, org) X(RayRecord, tmin)            \
  X(RayRecord, dir) X(RayRecord, tmax) X(HitRecord, t) X(HitRecord, prim) X(HitRecord, u) X(HitRecord, v)

#ifndef __OPENCL_VERSION__
static_assert(sizeof(BvhNode) == 32, "BvhNode is 32 bytes");
static_assert(sizeof(Primitive) == 48, "Primitive is 48 bytes");
static_assert(sizeof(PrimShading) == 16, "PrimShading is 16 bytes");
static_assert(sizeof(Material) == 32, "Material is 32 bytes");
static_assert(sizeof(Light) == 32, "Light is 32 bytes");
static_assert(sizeof(SceneHeader) == 112, "SceneHeader is 112 bytes");
static_assert(sizeof(PassStats) == 16, "PassStats is 16 bytes");
static_assert(sizeof(RayRecord) == 32, "RayRecord is 32 bytes");
static_assert(sizeof(HitRecord) == 16, "HitRecord is 16 bytes");
#endif

#endif
