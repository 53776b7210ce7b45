/* Small math helpers shared by every kernel. */
#ifndef PATHCL_MATH_CL
#define PATHCL_MATH_CL

#include "exact_math.cl"

#define PC_PI 3.14159265358979323846f
#define PC_INV_PI 0.31830988618379067154f
#define PC_MACHINE_EPSILON (FLT_EPSILON * 0.5f)

/* A large function with several callers, or a kernel's body (scene.cl's PC_KERNEL_BODY), compiled once and
 * called on x86 CPU devices (PoCL), where its inlined copies cost build time; GPU compilers decide. */
#ifdef __x86_64__
#define PC_OUT_OF_LINE __attribute__((noinline))
#else
#define PC_OUT_OF_LINE inline
#endif

/* pbrt's gamma(n): bound on the relative error of n floating-point operations. */
inline float error_gamma(int n) { return (n * PC_MACHINE_EPSILON) / (1.0f - n * PC_MACHINE_EPSILON); }

inline float max_component(float3 v) { return fmax(v.x, fmax(v.y, v.z)); }

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
inline float3 lane3_of(float3 v) { return v; }
inline float3 float3_of(float3 v) { return v; }

inline float luminance(float3 c) { return luminance_lanes(c); }

#endif
