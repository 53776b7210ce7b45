#pragma OPENCL FP_CONTRACT OFF
/* Kernels that only tests/exact_math_test.cpp builds: each function of exact_math.cl over input arrays,
 * once per element through the scalar overload (F_1) and once through each vector overload on the same
 * inputs packed N to a vector (F_N, one work item per vector), so that the test can check every lane
 * against the scalar result bit for bit. The geometric functions take their vectors packed N floats apart. */
#include "shared/types.h"
#include "exact_math.cl"

/* Kernel F_N for the function F (never a builtin's name, which the headers may define as a macro). */
#define PC_TEST_UNARY_N(F, N)                                                             \
  __kernel void F##_##N(__global const float* x, __global float* out) {                   \
    size_t i = get_global_id(0);                                                          \
    vstore##N(F(vload##N(i, x)), i, out);                                                 \
  }
#define PC_TEST_UNARY(F)                                                                  \
  __kernel void F##_1(__global const float* x, __global float* out) {                     \
    size_t i = get_global_id(0);                                                          \
    out[i] = F(x[i]);                                                                     \
  }                                                                                       \
  PC_TEST_UNARY_N(F, 2) PC_TEST_UNARY_N(F, 3) PC_TEST_UNARY_N(F, 4) PC_TEST_UNARY_N(F, 8) PC_TEST_UNARY_N(F, 16)

#define PC_TEST_BINARY_N(F, N)                                                            \
  __kernel void F##_##N(__global const float* x, __global const float* y, __global float* out) { \
    size_t i = get_global_id(0);                                                          \
    vstore##N(F(vload##N(i, x), vload##N(i, y)), i, out);                                 \
  }
#define PC_TEST_BINARY(F)                                                                 \
  __kernel void F##_1(__global const float* x, __global const float* y, __global float* out) { \
    size_t i = get_global_id(0);                                                          \
    out[i] = F(x[i], y[i]);                                                               \
  }                                                                                       \
  PC_TEST_BINARY_N(F, 2) PC_TEST_BINARY_N(F, 3) PC_TEST_BINARY_N(F, 4) PC_TEST_BINARY_N(F, 8) PC_TEST_BINARY_N(F, 16)

PC_TEST_UNARY(pc_sin)
PC_TEST_UNARY(pc_cos)
PC_TEST_UNARY(pc_acos)
PC_TEST_UNARY(pc_log)
PC_TEST_UNARY(pc_exp)
PC_TEST_UNARY(pc_exp2)
PC_TEST_UNARY(pc_erf)
PC_TEST_BINARY(pc_atan2)
PC_TEST_BINARY(pc_powr)

/* pc_sincos: sin to out, cos to out_cos. */
#define PC_TEST_SINCOS_N(N)                                                               \
  __kernel void pc_sincos_##N(__global const float* x, __global float* out, __global float* out_cos) { \
    size_t i = get_global_id(0);                                                          \
    float##N c;                                                                           \
    vstore##N(pc_sincos(vload##N(i, x), &c), i, out);                                     \
    vstore##N(c, i, out_cos);                                                             \
  }
__kernel void pc_sincos_1(__global const float* x, __global float* out, __global float* out_cos) {
  size_t i = get_global_id(0);
  float c;
  out[i] = pc_sincos(x[i], &c);
  out_cos[i] = c;
}
PC_TEST_SINCOS_N(2)
PC_TEST_SINCOS_N(3)
PC_TEST_SINCOS_N(4)
PC_TEST_SINCOS_N(8)
PC_TEST_SINCOS_N(16)

/* Vector functions of floatN vectors stored N floats apart. */
#define PC_TEST_GEOMETRIC(N)                                                              \
  __kernel void pc_dot_##N(__global const float* a, __global const float* b, __global float* out) { \
    size_t i = get_global_id(0);                                                          \
    out[i] = pc_dot(vload##N(i, a), vload##N(i, b));                                      \
  }                                                                                       \
  __kernel void pc_length_##N(__global const float* a, __global float* out) {                \
    size_t i = get_global_id(0);                                                          \
    out[i] = pc_length(vload##N(i, a));                                                   \
  }                                                                                       \
  __kernel void pc_normalize_##N(__global const float* a, __global float* out) {             \
    size_t i = get_global_id(0);                                                          \
    vstore##N(pc_normalize(vload##N(i, a)), i, out);                                      \
  }
PC_TEST_GEOMETRIC(2)
PC_TEST_GEOMETRIC(3)
PC_TEST_GEOMETRIC(4)
__kernel void pc_cross_3(__global const float* a, __global const float* b, __global float* out) {
  size_t i = get_global_id(0);
  vstore3(pc_cross(vload3(i, a), vload3(i, b)), i, out);
}
__kernel void pc_cross_4(__global const float* a, __global const float* b, __global float* out) {
  size_t i = get_global_id(0);
  vstore4(pc_cross(vload4(i, a), vload4(i, b)), i, out);
}

/* The lane geometry (lane3f, lane3f8, lane3f16) on float3s stored 3 floats apart, N per work item: per
 * vector, out[8 v ..] = dot(a, b), cross(a, b), length(a), normalize(a). */
#define PC_TEST_LANES3(V3, F, N)                                                                      \
  __kernel void lane3_geometric_##N(__global const float* a, __global const float* b, __global float* out) { \
    size_t i = get_global_id(0);                                                                      \
    float ax[N], ay[N], az[N], bx[N], by[N], bz[N], r[8][N];                                          \
    for (int j = 0; j < N; ++j) {                                                                     \
      float3 u = vload3(N * i + j, a), w = vload3(N * i + j, b);                                      \
      ax[j] = u.x, ay[j] = u.y, az[j] = u.z, bx[j] = w.x, by[j] = w.y, bz[j] = w.z;                   \
    }                                                                                                 \
    V3 va = lane3(PC_LOAD_##N(ax), PC_LOAD_##N(ay), PC_LOAD_##N(az));                                 \
    V3 vb = lane3(PC_LOAD_##N(bx), PC_LOAD_##N(by), PC_LOAD_##N(bz));                                 \
    V3 c = pc_cross(va, vb), n = pc_normalize(va);                                                    \
    F v[8] = {pc_dot(va, vb), c.x, c.y, c.z, pc_length(va), n.x, n.y, n.z};                            \
    for (int k = 0; k < 8; ++k) PC_STORE_##N(v[k], r[k]);                                             \
    for (int j = 0; j < N; ++j)                                                                       \
      for (int k = 0; k < 8; ++k) out[8 * (N * i + j) + k] = r[k][j];                                 \
  }
#define PC_LOAD_1(p) (p)[0]
#define PC_LOAD_8(p) vload8(0, p)
#define PC_LOAD_16(p) vload16(0, p)
#define PC_STORE_1(x, p) (p)[0] = (x)
#define PC_STORE_8(x, p) vstore8(x, 0, p)
#define PC_STORE_16(x, p) vstore16(x, 0, p)
PC_TEST_LANES3(lane3f, float, 1)
PC_TEST_LANES3(lane3f8, float8, 8)
PC_TEST_LANES3(lane3f16, float16, 16)

/* Throughput (the disabled benchmark in tests/exact_math_test.cpp): each work item evaluates EXPR, the
 * exact function or the builtin, on `count` arguments x derived from its id, and writes their sum so that
 * nothing is optimised away. */
#define PC_BENCH(NAME, TYPE, EXPR)                                                        \
  __kernel void bench_##NAME(uint count, float scale, __global float* out) {              \
    TYPE acc = 0.0f;                                                                      \
    float x0 = (float)get_global_id(0) * scale;                                           \
    for (uint j = 0; j < count; ++j) {                                                    \
      float x = x0 + (float)j * 0x1p-7f;                                                  \
      acc += EXPR;                                                                        \
    }                                                                                     \
    out[get_global_id(0)] = dot(acc, (TYPE)1.0f);                                         \
  }
PC_BENCH(pc_sin, float, pc_sin(x))
PC_BENCH(sin, float, sin(x))
PC_BENCH(pc_cos, float, pc_cos(x))
PC_BENCH(cos, float, cos(x))
static inline float pc_sincos_sum_(float x) {
  float c, s = pc_sincos(x, &c);
  return s + c;
}
static inline float sincos_sum_(float x) {
  float c, s = sincos(x, &c);
  return s + c;
}
PC_BENCH(pc_sincos, float, pc_sincos_sum_(x))
PC_BENCH(sincos, float, sincos_sum_(x))
PC_BENCH(pc_atan2, float, pc_atan2(x - 0.5f, 1.0f - x))
PC_BENCH(atan2, float, atan2(x - 0.5f, 1.0f - x))
PC_BENCH(pc_powr, float, pc_powr((x - floor(x)), x * 16.0f))
PC_BENCH(powr, float, powr((x - floor(x)), x * 16.0f))
PC_BENCH(pc_normalize, float3, pc_normalize((float3)(x - 0.5f, 1.0f - x, 0.25f)))
PC_BENCH(normalize, float3, normalize((float3)(x - 0.5f, 1.0f - x, 0.25f)))
