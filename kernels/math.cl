/* Small math helpers shared by every kernel. */
#ifndef PATHCL_MATH_CL
#define PATHCL_MATH_CL

#include "exact_math.cl"

#define PC_PI 3.14159265358979323846f
#define PC_INV_PI 0.31830988618379067154f
#define PC_MACHINE_EPSILON (FLT_EPSILON * 0.5f)

/* Every function of the kernels is static (internal linkage): PoCL compiles with -Dinline=, so an `inline`
 * function has external linkage there, and its front end compiled and optimised every one (548 in the
 * Cornell box's path program, of every lane width and integrator), called or not, before its linker
 * dropped them; static ones that nothing calls are never generated, and one with a single caller is
 * inlined into it (cold builds 0.82x for the path program, 0.70-0.85x for the other integrators).
 * PC_OUT_OF_LINE: a large function with several callers, or a kernel's body (scene.cl's PC_KERNEL_BODY),
 * compiled once and called on x86 CPU devices (PoCL), where its inlined copies cost build time; GPU
 * compilers decide. So are the path integrator's large stages (the surface, its material, light and BSDF
 * sampling), which as statics with one caller made one function too large to compile quickly (the
 * unspecialised program 1.1x slower to build), and the traversal of one tree (intersect.cl): inlined into
 * a kernel launched with PoCL's own local size, its stacks became per-item arrays of the work-group
 * function (82 MB of stack for the 3456 items of a test kernel). */
#ifdef __x86_64__
#define PC_OUT_OF_LINE static __attribute__((noinline))
#else
#define PC_OUT_OF_LINE static inline
#endif

/* pbrt's gamma(n): bound on the relative error of n floating-point operations. */
static inline float error_gamma(int n) { return (n * PC_MACHINE_EPSILON) / (1.0f - n * PC_MACHINE_EPSILON); }

static inline float max_component(float3 v) { return fmax(v.x, fmax(v.y, v.z)); }

/* Written once over lanes (V3 lane3f/lane3f8/lane3f16 of exact_math.cl, F, I their float and int types,
 * for issue 15's lane-generic kernel), branches as per-lane selects; the float3 functions below are the
 * one-lane instances, so every lane gets their bits (tests/exact_math_test.cpp, LaneHelpersGiveTheFloat3Bits). */
#define PC_LANE_W 1
#include "templates/math.cl"
#define PC_LANE_W 8
#include "templates/math.cl"
#define PC_LANE_W 16
#include "templates/math.cl"

/* A float3 as one lane and back (the same type: kept where a call reads better as a conversion). */
static inline float3 lane3_of(float3 v) { return v; }
static inline float3 float3_of(float3 v) { return v; }

static inline float luminance(float3 c) { return luminance_lanes(c); }

#endif
