#pragma OPENCL FP_CONTRACT OFF
/* Math functions that give the same bits on every conformant OpenCL implementation (PoCL, Oclgrind, GPU
 * drivers), unlike the builtins, whose precision is implementation-defined.
 *
 * Built only from operations whose results IEEE 754 and OpenCL define exactly: + - * (contraction off, the
 * pragma above), / and sqrt (correctly rounded: build with -cl-fp32-correctly-rounded-divide-sqrt where the
 * device supports it), fabs, copysign, rint, fmin/fmax, comparisons, select, bit casts, integer arithmetic
 * (mul_hi, clz) and int<->float conversions of values that convert exactly. Never fma/mad, transcendental,
 * native_ or half_ builtins.
 *
 * Each algorithm is written once, as a macro over a float type T (float .. float16), its int type I and
 * uint type U, with select() instead of branches that could differ per lane, so every lane of a vector
 * call does exactly the operations of the scalar call: the vector width never changes a result. The only
 * branches (the Payne-Hanek reduction, erf's tail) are taken when any lane needs them and their results
 * are selected per lane. Masks come from comparisons (1 for scalars, -1 for vectors: select() takes both,
 * and & | ^ ! keep both conventions; never ~ on a mask).
 *
 * Denormals: no result depends on whether a device flushes them. Denormal inputs are read as zeros of
 * their sign (decided on the bits, so a device that flushes reads the same); intermediates of normal
 * inputs stay normal wherever they could change a result (where a denormal could appear, it is below half
 * an ulp of what it is added to, which rounds the same whether it is kept or flushed); results below
 * FLT_MIN are returned as zeros of their sign (a quotient or product near FLT_MIN is decided before it can
 * round into, or be flushed from, the denormal range). NaN results are the quiet NaN 0x7fc00000,
 * whatever the input's payload.
 *
 * Error bounds are in ulp of the correctly rounded result, over the whole input range, as measured by
 * tests/exact_math_test.cpp and exhaustively over all floats for the one-argument functions. */
#ifndef PATHCL_EXACT_MATH_CL
#define PATHCL_EXACT_MATH_CL

#define PC_OVL __attribute__((overloadable))
#define PC_NAN_BITS 0x7fc00000u

/* pi/2, pi and 1/ln 2 as the sum of two floats (hi + lo). */
#define PC_PIO2_HI 0x1.921fb6p+0f
#define PC_PIO2_LO -0x1.777a5cp-25f
#define PC_PI_HI 0x1.921fb6p+1f
#define PC_PI_LO -0x1.777a5cp-24f
#define PC_INV_LN2_HI 0x1.715476p+0f
#define PC_INV_LN2_LO 0x1.4ae0cp-26f

static inline PC_OVL int pc_any_(int m) { return m != 0; }
#define PC_EM_ANY(I) \
  static inline PC_OVL int pc_any_(I m) { return any(m); }

/* pi/2 in pieces (the reduction of sin and cos, templates/exact_math.cl): four of at most 12 bits (k * piece
 * is exact for k < 4096), the last one 24 bits. */
#define PC_CW1 0x1.922p+0f
#define PC_CW2 -0x1.28p-18f
#define PC_CW3 -0x1.778p-25f
#define PC_CW4 0x1.69p-39f
#define PC_CW5 -0x1.ee59dap-50f

PC_EM_ANY(int2)
PC_EM_ANY(int3)
#if defined(__clang__) && defined(__AVX512DQ__) && defined(__AVX512VL__)
/* x86 CPUs with AVX-512 (PoCL, Intel's CPU runtime): a mask of 4, 8 or 16 lanes (-1 or 0 each) as its sign
 * bits, which the compiler takes straight from the comparison's mask register (one kmov); also
 * kernels/lanes.cl's pc_lane_bits. */
#define PC_SIGN_BIT_MASKS 1
static inline PC_OVL uint pc_sign_bits_(int4 m) { return (uint)__builtin_ia32_cvtd2mask128(m); }
static inline PC_OVL uint pc_sign_bits_(int8 m) { return (uint)__builtin_ia32_cvtd2mask256(m); }
static inline PC_OVL uint pc_sign_bits_(int16 m) { return (uint)__builtin_ia32_cvtd2mask512(m); }
static inline PC_OVL int pc_any_(int4 m) { return pc_sign_bits_(m) != 0u; }
static inline PC_OVL int pc_any_(int8 m) { return pc_sign_bits_(m) != 0u; }
static inline PC_OVL int pc_any_(int16 m) { return pc_sign_bits_(m) != 0u; }
#elif defined(__clang__) && defined(__AVX__)
/* x86 CPUs with AVX and without AVX-512 (PoCL on AVX2 CPUs): the sign bits by vmovmskps (which LLVM 15 lowers
 * to a pack and a vpmovmskb: still fewer instructions than the byte narrowing and multiplication below). The
 * path integrator's 8 lanes on AVX2 code: Cornell box 8 %, glass-metal 5 % more samples/s. */
#define PC_SIGN_BIT_MASKS 1
static inline PC_OVL uint pc_sign_bits_(int4 m) { return (uint)__builtin_ia32_movmskps(as_float4(m)); }
static inline PC_OVL uint pc_sign_bits_(int8 m) { return (uint)__builtin_ia32_movmskps256(as_float8(m)); }
static inline PC_OVL uint pc_sign_bits_(int16 m) { return pc_sign_bits_(m.lo) | pc_sign_bits_(m.hi) << 8; }
static inline PC_OVL int pc_any_(int4 m) { return pc_sign_bits_(m) != 0u; }
static inline PC_OVL int pc_any_(int8 m) { return pc_sign_bits_(m) != 0u; }
static inline PC_OVL int pc_any_(int16 m) { return pc_sign_bits_(m) != 0u; }
#else
/* Masks of 4, 8 and 16 lanes (-1 or 0 each) narrowed to bytes and read as one or two integers: a few vector
 * instructions, where PoCL's any() is a loop over the lanes (it took a tenth of the 16-lane path kernel's
 * time). */
static inline PC_OVL int pc_any_(int4 m) { return as_uint(convert_char4(m)) != 0u; }
static inline PC_OVL int pc_any_(int8 m) { return as_ulong(convert_char8(m)) != 0ul; }
static inline PC_OVL int pc_any_(int16 m) {
  ulong2 b = as_ulong2(convert_char16(m));
  return (b.x | b.y) != 0ul;
}
#endif
/* The functions above the bit casts (bit casts, error-free transformations, sin, cos, atan2, acos, log, exp2,
 * exp, powr, erf) for each type. */
#define PC_LANE_W 1
#include "templates/exact_math.cl"
#define PC_LANE_W 2
#include "templates/exact_math.cl"
#define PC_LANE_W 3
#include "templates/exact_math.cl"
#define PC_LANE_W 4
#include "templates/exact_math.cl"
#define PC_LANE_W 8
#include "templates/exact_math.cl"
#define PC_LANE_W 16
#include "templates/exact_math.cl"

/* ---- dot, cross, length, normalize ----------------------------------------------------------------------
 * pc_dot (float2/3/4): the products, then their sum from left to right, each rounded once (not fused), so
 * the result is the one of that written-out sum: no error bound beyond the rounding of each operation.
 * pc_cross (float3; float4 with w = 0): a.y b.z - a.z b.y, ... the same way.
 * Denormal inputs are zeros, products at most FLT_MIN and sums below it are zeros of their sign, so a
 * device that flushes denormals gets the same bits. */
static inline PC_OVL float pc_dot(float2 a, float2 b) {
  float2 p = pc_flush_product_(pc_flush_(a) * pc_flush_(b));
  return pc_flush_(p.x + p.y);
}
static inline PC_OVL float pc_dot(float3 a, float3 b) {
  float3 p = pc_flush_product_(pc_flush_(a) * pc_flush_(b));
  return pc_flush_(pc_flush_(p.x + p.y) + p.z);
}
static inline PC_OVL float pc_dot(float4 a, float4 b) {
  float4 p = pc_flush_product_(pc_flush_(a) * pc_flush_(b));
  return pc_flush_(pc_flush_(pc_flush_(p.x + p.y) + p.z) + p.w);
}
static inline PC_OVL float3 pc_cross(float3 a, float3 b) {
  a = pc_flush_(a);
  b = pc_flush_(b);
  return pc_flush_(pc_flush_product_(a.yzx * b.zxy) - pc_flush_product_(a.zxy * b.yzx));
}
static inline PC_OVL float4 pc_cross(float4 a, float4 b) { return (float4)(pc_cross(a.xyz, b.xyz), 0.0f); }

/* pc_length: sqrt of the sum of squares, error <= (n + 2) / 2 ulp for n components (a priori: n roundings
 * in the sum, halved by the square root, plus its own; 1.1 to 1.4 ulp measured); a zero vector has length
 * +0, one with an infinite component +inf, NaN components give NaN.
 * pc_normalize: v / sqrt(v . v), each component's error <= (n + 4) / 2 ulp (the length's and the
 * division's; 2.1 to 2.3 ulp measured); a zero vector is returned as it is (its zeros keep their signs);
 * infinite components become +-1 and the others +-0 before normalising; NaN -> all NaN; components
 * below FLT_MIN -> +-0.
 * The sum of squares is taken as it is when the largest |component| lies in [2^-40, 2^40) (squares of
 * smaller components may be denormal, but are below half an ulp of the largest square, so flushing them
 * cannot change the sum), otherwise after an exact scaling by a power of two that brings it to [2, 4).
 * A component is divided by length 2^-24, so a quotient below FLT_MIN is recognised while it is still
 * normal (2^24 times larger), then scaled back exactly. */
static inline PC_OVL uint pc_max_component_(uint2 a) { return max(a.x, a.y); }
static inline PC_OVL uint pc_max_component_(uint3 a) { return max(max(a.x, a.y), a.z); }
static inline PC_OVL uint pc_max_component_(uint4 a) { return max(max(max(a.x, a.y), a.z), a.w); }
static inline PC_OVL float pc_sum_of_squares_(float2 v) { return v.x * v.x + v.y * v.y; }
static inline PC_OVL float pc_sum_of_squares_(float3 v) { return v.x * v.x + v.y * v.y + v.z * v.z; }
static inline PC_OVL float pc_sum_of_squares_(float4 v) { return v.x * v.x + v.y * v.y + v.z * v.z + v.w * v.w; }

#define PC_EM_GEOMETRIC(V, U, N)                                                                          \
  static inline PC_OVL float pc_length(V v) {                                                             \
    U ab = as_uint##N(v) & 0x7fffffffu;                                                                   \
    ab = select(ab, (U)0u, ab < 0x00800000u);                                                             \
    V va = as_float##N(ab);                                                                               \
    uint mb = pc_max_component_(ab);                                                                      \
    if (mb - 0x2b800000u < 0x28000000u) return sqrt(pc_sum_of_squares_(va)); /* max in [2^-40, 2^40) */   \
    if (mb == 0u) return 0.0f;                                                                            \
    if (mb > 0x7f800000u) return as_float(PC_NAN_BITS);                                                   \
    if (mb == 0x7f800000u) return INFINITY;                                                               \
    float s = as_float((255u - (mb >> 23)) << 23); /* max * s in [2, 4) */                                \
    return sqrt(pc_sum_of_squares_(va * s)) / s;                                                          \
  }                                                                                                       \
  static inline PC_OVL V pc_normalize(V v) {                                                              \
    U b = as_uint##N(v), ab = b & 0x7fffffffu;                                                            \
    ab = select(ab, (U)0u, ab < 0x00800000u);                                                             \
    V v0 = as_float##N(ab | (b & 0x80000000u)), vs = v0;                                                  \
    uint mb = pc_max_component_(ab);                                                                      \
    if (mb - 0x2b800000u >= 0x28000000u) { /* max outside [2^-40, 2^40): zero, inf, NaN or far from 1 */  \
      if (mb == 0u) return v0;                                                                            \
      if (mb > 0x7f800000u) return as_float##N((U)PC_NAN_BITS);                                           \
      if (mb == 0x7f800000u)                                                                              \
        vs = select(copysign((V)0.0f, v0), copysign((V)1.0f, v0), ab == 0x7f800000u);                     \
      else                                                                                                \
        vs = v0 * as_float((255u - (mb >> 23)) << 23);                                                    \
    }                                                                                                     \
    V q = vs / (sqrt(pc_sum_of_squares_(vs)) * 0x1p-24f);                                                 \
    return select(q * 0x1p-24f, copysign((V)0.0f, v0), fabs(q) < 0x1p-102f);                              \
  }
PC_EM_GEOMETRIC(float2, uint2, 2)
PC_EM_GEOMETRIC(float3, uint3, 3)
PC_EM_GEOMETRIC(float4, uint4, 4)


/* ---- The same over lanes: 3-vectors stored by component (x, y, z each a float, float8 or float16 of the
 * lanes' values), for issue 15's lane-generic kernel. Every lane does exactly the operations of the
 * float3 function above (the same products, sums and their order, the same flushes); its branches are
 * selects per lane. So lane j of pc_normalize(lane3f8 v) is pc_normalize of lane j's float3, bit for bit
 * (tests/exact_math_test.cpp, LaneGeometryGivesTheFloat3Bits). */
/* One lane is a float3: its operations are the float3 functions above (on CPU devices one SSE register
 * per vector, on GPUs scalars), with lane3(x, y, z) its constructor. */
typedef float3 lane3f;
static inline PC_OVL float3 lane3(float x, float y, float z) { return (float3)(x, y, z); }
typedef struct { float8 x, y, z; } lane3f8;
typedef struct { float16 x, y, z; } lane3f16;

#define PC_EM_LANES3(V3, F, I, U, N)                                                                      \
  static inline PC_OVL V3 lane3(F x, F y, F z) {                                                          \
    V3 v;                                                                                                 \
    v.x = x;                                                                                              \
    v.y = y;                                                                                              \
    v.z = z;                                                                                              \
    return v;                                                                                             \
  }                                                                                                       \
  /* Whether every component of a and b is 0 or at least 2^-50 in magnitude, in every lane (nearly        \
     always). Then each product is 0 or at least 2^-100, a multiple of 2^-123, and so is every sum or     \
     difference of them, rounded or not: nothing below FLT_MIN arises, and the flushes of pc_dot and      \
     pc_cross, which lengthened their dependency chains, would change no bit. (|x| - 1 as an unsigned     \
     integer puts 0 at the top.) */                                                                       \
  static inline PC_OVL U pc_lane_tiny_key_(F x) { return (as_uint##N(x) & 0x7fffffffu) - 1u; }            \
  static inline PC_OVL bool pc_no_tiny_components_(V3 a, V3 b) {                                          \
    U k = min(min(min(pc_lane_tiny_key_(a.x), pc_lane_tiny_key_(a.y)), pc_lane_tiny_key_(a.z)),           \
              min(min(pc_lane_tiny_key_(b.x), pc_lane_tiny_key_(b.y)), pc_lane_tiny_key_(b.z)));          \
    return all(k >= 0x267fffffu); /* 2^-50: 0x26800000 */                                                 \
  }                                                                                                       \
  static inline PC_OVL F pc_dot(V3 a, V3 b) {                                                             \
    if (pc_no_tiny_components_(a, b)) return (a.x * b.x + a.y * b.y) + a.z * b.z;                         \
    F px = pc_flush_product_(pc_flush_(a.x) * pc_flush_(b.x));                                            \
    F py = pc_flush_product_(pc_flush_(a.y) * pc_flush_(b.y));                                            \
    F pz = pc_flush_product_(pc_flush_(a.z) * pc_flush_(b.z));                                            \
    return pc_flush_(pc_flush_(px + py) + pz);                                                            \
  }                                                                                                       \
  static inline PC_OVL V3 pc_cross(V3 a, V3 b) {                                                          \
    if (pc_no_tiny_components_(a, b))                                                                     \
      return lane3(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);                  \
    F ax = pc_flush_(a.x), ay = pc_flush_(a.y), az = pc_flush_(a.z);                                      \
    F bx = pc_flush_(b.x), by = pc_flush_(b.y), bz = pc_flush_(b.z);                                      \
    return lane3(pc_flush_(pc_flush_product_(ay * bz) - pc_flush_product_(az * by)),                      \
                 pc_flush_(pc_flush_product_(az * bx) - pc_flush_product_(ax * bz)),                      \
                 pc_flush_(pc_flush_product_(ax * by) - pc_flush_product_(ay * bx)));                     \
  }                                                                                                       \
  /* |component| bits with denormals as zeros, and the largest of them. */                               \
  static inline PC_OVL U pc_lane_abs_bits_(F x) {                                                         \
    U a = as_uint##N(x) & 0x7fffffffu;                                                                    \
    return select(a, (U)(0u), a < 0x00800000u);                                                           \
  }                                                                                                       \
  static inline PC_OVL F pc_lane_sum_of_squares_(F x, F y, F z) { return x * x + y * y + z * z; }
/* pc_length and pc_normalize of 8 or 16 lanes; those of one lane are the float3 functions, whose early
 * returns are faster than these selects and give the same bits. */
#define PC_EM_LANES3_LENGTH(V3, F, I, U, N)                                                               \
  static inline PC_OVL F pc_length(V3 v) {                                                                \
    U ax = pc_lane_abs_bits_(v.x), ay = pc_lane_abs_bits_(v.y), az = pc_lane_abs_bits_(v.z);              \
    F vx = as_float##N(ax), vy = as_float##N(ay), vz = as_float##N(az);                                   \
    U mb = max(max(ax, ay), az);                                                                          \
    F s = as_float##N((255u - (mb >> 23u)) << 23u); /* max * s in [2, 4) */                               \
    F direct = sqrt(pc_lane_sum_of_squares_(vx, vy, vz));                                                 \
    F scaled = sqrt(pc_lane_sum_of_squares_(vx * s, vy * s, vz * s)) / s;                                 \
    F r = select(scaled, direct, mb - 0x2b800000u < 0x28000000u); /* max in [2^-40, 2^40) */             \
    r = select(r, (F)(0.0f), mb == 0u);                                                                   \
    r = select(r, as_float##N((U)(PC_NAN_BITS)), mb > 0x7f800000u);                                       \
    return select(r, (F)(INFINITY), mb == 0x7f800000u);                                                   \
  }                                                                                                       \
  static inline PC_OVL V3 pc_normalize(V3 v) {                                                            \
    U bx = as_uint##N(v.x), by = as_uint##N(v.y), bz = as_uint##N(v.z);                                   \
    U ax = pc_lane_abs_bits_(v.x), ay = pc_lane_abs_bits_(v.y), az = pc_lane_abs_bits_(v.z);              \
    F v0x = as_float##N(ax | (bx & 0x80000000u)), v0y = as_float##N(ay | (by & 0x80000000u));             \
    F v0z = as_float##N(az | (bz & 0x80000000u));                                                         \
    U mb = max(max(ax, ay), az);                                                                          \
    I zero = mb == 0u, nan = mb > 0x7f800000u, inf = mb == 0x7f800000u;                                   \
    /* max outside [2^-40, 2^40), finite and not zero: scaled by a power of two to [2, 4) */              \
    I far = (mb - 0x2b800000u >= 0x28000000u) & !zero & !nan & !inf;                                      \
    F s = as_float##N((255u - (mb >> 23u)) << 23u);                                                       \
    F sx = select(v0x, v0x * s, far), sy = select(v0y, v0y * s, far), sz = select(v0z, v0z * s, far);     \
    /* infinite components become +-1, the others +-0 */                                                  \
    sx = select(sx, select(copysign((F)(0.0f), v0x), copysign((F)(1.0f), v0x), ax == 0x7f800000u), inf);  \
    sy = select(sy, select(copysign((F)(0.0f), v0y), copysign((F)(1.0f), v0y), ay == 0x7f800000u), inf);  \
    sz = select(sz, select(copysign((F)(0.0f), v0z), copysign((F)(1.0f), v0z), az == 0x7f800000u), inf);  \
    F den = sqrt(pc_lane_sum_of_squares_(sx, sy, sz)) * 0x1p-24f;                                         \
    F qx = sx / den, qy = sy / den, qz = sz / den;                                                        \
    F nan_value = as_float##N((U)(PC_NAN_BITS));                                                          \
    qx = select(qx * 0x1p-24f, copysign((F)(0.0f), v0x), fabs(qx) < 0x1p-102f);                           \
    qy = select(qy * 0x1p-24f, copysign((F)(0.0f), v0y), fabs(qy) < 0x1p-102f);                           \
    qz = select(qz * 0x1p-24f, copysign((F)(0.0f), v0z), fabs(qz) < 0x1p-102f);                           \
    return lane3(select(select(qx, v0x, zero), nan_value, nan), select(select(qy, v0y, zero), nan_value, nan), \
                 select(select(qz, v0z, zero), nan_value, nan));                                          \
  }
PC_EM_LANES3(lane3f8, float8, int8, uint8, 8)
PC_EM_LANES3(lane3f16, float16, int16, uint16, 16)
PC_EM_LANES3_LENGTH(lane3f8, float8, int8, uint8, 8)
PC_EM_LANES3_LENGTH(lane3f16, float16, int16, uint16, 16)
#undef PC_EM_LANES3
#undef PC_EM_LANES3_LENGTH

#endif
