/* Structs of light transport (the `light` integrator, and later BDPT and photon merging) shared byte for
 * byte by the host and the kernels, under the rules of types.h. They live apart from types.h so that the
 * path integrator's kernel source does not change because these exist (its build is the same bytes). */
#ifndef PATHCL_SHARED_LIGHT_TYPES_H
#define PATHCL_SHARED_LIGHT_TYPES_H

/* Needs shared/types.h first (pc_float4, pc_uint); the kernel source assembler finds files by their name
 * under kernels/, the host by its include path, so neither includes it from here. */

/* Integrators (RenderOptions::integrator, render.integrator of the scene file). */
#define PC_INTEGRATOR_PATH 0u
#define PC_INTEGRATOR_LIGHT 1u
#define PC_INTEGRATOR_BDPT 2u
#define PC_INTEGRATOR_VCM 3u
#define PC_INTEGRATOR_BPM 4u
#define PC_INTEGRATOR_SPPM 5u
#define PC_INTEGRATOR_INSTANT_RADIOSITY 6u
#define PC_INTEGRATOR_RADIOSITY 7u
#define PC_INTEGRATOR_MLT 8u

/* The strategies of the merging integrators (LightTransportHeader.vcm_mode; kernels/vcm.cl). */
#define PC_VCM_CONNECT 1u /* vertex connection: BDPT's strategies */
#define PC_VCM_MERGE 2u   /* vertex merging */
#define PC_VCM_SPPM 4u    /* progressive photon mapping: merge at the first non-delta camera vertex only */

/* Blocks of the device's prefix sums (kernels/scan.cl: vcm's grid, mlt's bootstrap); an array of n entries
 * takes n + 1 + PC_SCAN_BLOCKS. */
#define PC_SCAN_BLOCKS 256u

/* Buckets of vcm's hash grid per light path of a unit (kernels/vcm.cl's grid_table). */
#define PC_GRID_BUCKETS_PER_PATH 4u

/* The splat film: per pixel PC_SPLAT_WORDS unsigned 64-bit fixed-point sums (each two uint words, low
 * word first), added with integer atomics in any order to the same bits:
 *   [0, 3)  RGB of the even-numbered samples' splats, in units of 1 / splat_scale
 *   [3, 6)  RGB of the odd-numbered samples' splats
 *   [6, 9)  RGB sums of the squared splats, in units of 1 / square_scale (the variance channels)
 *   [9, 12) RGB of the camera subpaths' contributions alone, both parities (BDPT; 0 for light tracing):
 *           a pixel's camera contribution is one sample per sample, its light splats come from many
 *           paths, and the variance needs the two means apart
 * A sum is kept below 2^63; reaching it counts an overflow (SplatStats.overflows, a hazard). */
#define PC_SPLAT_WORDS 12u

/* What the light-transport kernels need beside the SceneHeader: the scene's bounding sphere (directional
 * and environment light paths start on a disk of its radius), the fixed-point scales of the splat film and
 * the number of lights in the emission distribution.
 * only_strategy: PC_INVALID for BDPT's every strategy; else (tests) s + (t << 16) of the one strategy it
 * takes, unweighted.
 * The merging integrators (kernels/vcm.cl): iteration i (the sample index) merges within radius
 * radius * (i + 1)^((alpha - 1) / 2), taking the strategies of vcm_mode (PC_VCM_*), merging's density
 * scaled by merge_mis in the MIS weights (vcm.cl's iteration_factors).
 * The gathering integrators (kernels/gather.cl): light_paths per iteration, instant radiosity's clamp of
 * the geometry term (0: none), radiosity's fixed-point scale of its per-triangle power sums and whether its
 * camera paths gather (final_gather) or show each triangle's radiosity.
 * Metropolis (kernels/mlt.cl): bootstrap states per depth, the large steps' probability and the small
 * steps' largest move.
 * bounds (16) + splat_scale (4) + square_scale (4) + light_count (4) + only_strategy (4) + radius (4) +
 * alpha (4) + vcm_mode (4) + light_paths (4) + clamp (4) + bin_scale (4) + final_gather (4) + bootstrap (4)
 * + large_step (4) + mutation_size (4) + merge_mis (4) + pad (4) = 80 bytes. */
typedef struct {
  pc_float4 bounds;   /* xyz: centre of the scene's bounding sphere (device coordinates), w: its radius */
  float splat_scale;  /* fixed-point units per unit of pixel value (a power of two) */
  float square_scale; /* the same for the squared splats (a power of two) */
  pc_uint light_count;
  pc_uint only_strategy;
  float radius;       /* the first iteration's merging radius (device units) */
  float alpha;        /* the radius's reduction exponent */
  pc_uint vcm_mode;
  pc_uint light_paths; /* the gathering integrators' light paths per iteration */
  float clamp;         /* instant radiosity: the largest geometry term cos cos / d^2 (0: unclamped) */
  float bin_scale;     /* radiosity: fixed-point units per unit of power (a power of two) */
  pc_uint final_gather;
  pc_uint bootstrap;     /* mlt */
  float large_step;
  float mutation_size;
  float merge_mis;       /* vcm: merging's factor in its MIS weights (1: SmallVCM's balance heuristic; bpm, sppm: 1) */
  pc_uint pad;
} LightTransportHeader;

/* Statistics of one light-tracing work unit, added with integer atomics: rays (64 bits as two words),
 * splats dropped for being NaN, infinite or negative, fixed-point overflows (a splat too large for the
 * scale, or a sum that reached 2^63) and the light vertices kept (bdpt, the merging integrators).
 * rays_lo .. light_vertices (7 x 4) + pad (4) = 32 bytes. */
typedef struct {
  pc_uint rays_lo;
  pc_uint rays_hi;
  pc_uint nan_splats;
  pc_uint inf_splats;
  pc_uint negative_splats;
  pc_uint overflows;
  pc_uint light_vertices;
  pc_uint pad;
} SplatStats;

/* A non-delta vertex of a light subpath, kept for the camera subpaths to connect to or merge with
 * (bdpt.cl, vcm.cl) in a buffer of max_depth slots per light path of a unit: what evaluating its BSDF
 * towards any direction needs, its throughput, and its partial MIS quantities dVCM, dVC and dVM
 * (Georgiev, "Implementing Vertex Connection and Merging", 2012). 6 x 16 + 4 x 4 = 112 bytes. */
typedef struct {
  pc_float4 p;     /* xyz: position; w: the largest component of its rounding-error bound */
  pc_float4 ng;    /* xyz: geometric normal (front side); w: dVCM */
  pc_float4 ns;    /* xyz: shading normal; w: dVC */
  pc_float4 wl;    /* xyz: unit direction back along the light path; w: dVM */
  pc_float4 beta;  /* xyz: throughput arriving at the vertex (emission weight and the scattering before it) */
  pc_float4 color; /* xyz: the material's colour here (textures and vertex colours applied) */
  pc_uint material, prim, instance;
  pc_uint length; /* scattering events of the light subpath up to and including this vertex */
} LightVertex;

#define PC_LIGHT_LAYOUT_STRUCTS(X) X(LightTransportHeader) X(SplatStats) X(LightVertex)
#define PC_LIGHT_LAYOUT_FIELDS(X)                                                                           \
  X(LightTransportHeader, bounds) X(LightTransportHeader, splat_scale) X(LightTransportHeader, square_scale) \
  X(LightTransportHeader, light_count) X(LightTransportHeader, only_strategy) X(LightTransportHeader, radius) \
  X(LightTransportHeader, alpha) X(LightTransportHeader, vcm_mode) X(LightTransportHeader, light_paths)       \
  X(LightTransportHeader, clamp) X(LightTransportHeader, bin_scale) X(LightTransportHeader, final_gather)         \
  X(LightTransportHeader, bootstrap) X(LightTransportHeader, large_step) X(LightTransportHeader, mutation_size) X(LightTransportHeader, merge_mis) X(LightVertex, wl) X(LightVertex, material) \
  X(LightVertex, length) X(SplatStats, light_vertices) X(SplatStats, rays_lo) X(SplatStats, rays_hi) X(SplatStats, nan_splats) \
  X(SplatStats, inf_splats) X(SplatStats, negative_splats) X(SplatStats, overflows)

#ifndef __OPENCL_VERSION__
static_assert(sizeof(LightTransportHeader) == 80, "LightTransportHeader is 80 bytes");
static_assert(sizeof(SplatStats) == 32, "SplatStats is 32 bytes");
static_assert(sizeof(LightVertex) == 112, "LightVertex is 112 bytes");
#endif

#endif
