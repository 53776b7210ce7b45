/* Lanes (issue 15): a work item of the path integrator renders W = PC_LANES paths at once, one per lane
 * of the OpenCL vector types (16 or 8 on CPU devices, whose vector units then take every lane in one
 * instruction; 1 on GPUs, where the vector types are scalars and the code is the one-path kernel). A
 * program is built for one W (-DPC_LANES, runtime/device_worker.cpp; 1 when it is not set), and the code
 * above the building blocks (the bounce, light choice and sampling, the surface, the material and the BSDF
 * dispatch) is written once over this program's lane types:
 *   LaneF, LaneI, LaneU   float, int, uint for W = 1; floatW, intW, uintW otherwise
 *   Lane3                 a 3-vector by component (exact_math.cl's lane3f, lane3f8, lane3f16)
 * Every lane does the operations of the one-lane program, so a pixel is the same bits at every W.
 * Masks follow exact_math.cl: comparisons give 1 (W = 1) or -1 (vectors), select() takes both, and
 * & | ! keep both (never ~ on a mask). The building blocks below (lane bits, lane access, reductions) are
 * defined for every width, the rest for this program's. */
#ifndef PATHCL_LANES_CL
#define PATHCL_LANES_CL

#include "exact_math.cl"

/* ---- For every width: a mask as bits (bit j: lane j set) and back, one lane by runtime index, the
 * smallest lane ----------------------------------------------------------------------------------- */
static inline PC_OVL uint pc_lane_bits(int m) { return m != 0 ? 1u : 0u; }
static inline PC_OVL int pc_lanes_of_bits(uint bits, int like) { return (int)(bits & 1u); }
static inline PC_OVL float pc_lane(float x, uint j) { return x; }
static inline PC_OVL uint pc_lane(uint x, uint j) { return x; }
static inline PC_OVL float pc_permute(float x, uint src) { return x; }
static inline PC_OVL uint pc_permute(uint x, uint src) { return x; }
static inline PC_OVL float pc_with_lane(float x, uint j, float value) { return value; }
static inline PC_OVL uint pc_with_lane(uint x, uint j, uint value) { return value; }

/* The least of the lanes of x, which holds no NaN: plain comparisons (vminps), where fmin's NaN rules
 * cost a compare and a blend at every step. */
static inline PC_OVL float2 pc_min_of_numbers(float2 a, float2 b) { return select(a, b, b < a); }
static inline PC_OVL float4 pc_min_of_numbers(float4 a, float4 b) { return select(a, b, b < a); }
static inline PC_OVL float8 pc_min_of_numbers(float8 a, float8 b) { return select(a, b, b < a); }
static inline PC_OVL float pc_min_lanes(float2 x) { return x.y < x.x ? x.y : x.x; }
static inline PC_OVL float pc_min_lanes(float4 x) { return pc_min_lanes(pc_min_of_numbers(x.lo, x.hi)); }

/* A mask of 8 or 16 lanes as bits, on the critical path of every BVH node. */
#ifdef PC_SIGN_BIT_MASKS
/* The sign bits (exact_math.cl): one kmov with AVX-512, a vmovmskps's few with AVX, where the form below is
 * seven. */
static inline PC_OVL uint pc_lane_bits(int8 m) { return pc_sign_bits_(m); }
static inline PC_OVL uint pc_lane_bits(int16 m) { return pc_sign_bits_(m); }
#else
/* The lanes as bytes 0 or 1: the multiplication puts byte j's bit into bit 56 + j (the partial products
 * land on distinct bits, so nothing carries). Fewer instructions than OR-ing the lanes' bit values. */
static inline uint pc_bits_of_bytes_(ulong bytes) { return (uint)((bytes * 0x0102040810204080ul) >> 56); }
static inline PC_OVL uint pc_lane_bits(int8 m) { return pc_bits_of_bytes_(as_ulong(convert_uchar8(m & 1))); }
static inline PC_OVL uint pc_lane_bits(int16 m) {
  ulong2 b = as_ulong2(convert_uchar16(m & 1));
  return pc_bits_of_bytes_(b.x) | pc_bits_of_bytes_(b.y) << 8;
}
#endif
/* The index of the lowest bit set in x (x != 0): a form that compilers turn into one count of trailing zeros
 * (OpenCL 1.2 has no ctz). */
static inline uint pc_lowest_bit(uint x) { return popcount(~x & (x - 1u)); }
#define PC_LANE_REDUCTIONS(F, I, U, N, BITS)                                                              \
  static inline PC_OVL I pc_lanes_of_bits(uint bits, I like) { return ((U)(bits) & BITS) != (U)(0u); }   \
  static inline PC_OVL float pc_min_lanes(F x) { return pc_min_lanes(pc_min_of_numbers(x.lo, x.hi)); }
PC_LANE_REDUCTIONS(float8, int8, uint8, 8, (uint8)(1u, 2u, 4u, 8u, 16u, 32u, 64u, 128u))
PC_LANE_REDUCTIONS(float16, int16, uint16, 16,
                   (uint16)(1u, 2u, 4u, 8u, 16u, 32u, 64u, 128u, 256u, 512u, 1024u, 2048u, 4096u, 8192u, 16384u, 32768u))
#undef PC_LANE_REDUCTIONS

/* A lane of a vector by runtime index, lanes rearranged, and a vector with one lane replaced. Where clang
 * targets AVX2 (8 lanes) or AVX-512 (16), pc_permute (lane src[j] of x in each lane j, src < the width) is
 * one vpermps or vpermd, and pc_lane reads a float lane with it: through memory, the load waits for the
 * vector's store to forward (on the BVH nodes' critical path: the 8-wide tree's bounce rays 5 % faster on
 * AVX2 code). */
#define PC_LANE_WRITE(T, S, N)                                                                            \
  static inline PC_OVL T pc_with_lane(T x, uint j, S value) {                                             \
    S a[N];                                                                                               \
    vstore##N(x, 0, a);                                                                                   \
    a[j] = value;                                                                                         \
    return vload##N(0, a);                                                                                \
  }
#define PC_LANE_READ_BY_MEMORY(T, S, N)                                                                   \
  static inline PC_OVL S pc_lane(T x, uint j) {                                                           \
    S a[N];                                                                                               \
    vstore##N(x, 0, a);                                                                                   \
    return a[j];                                                                                          \
  }
#define PC_PERMUTE_BY_MEMORY(T, S, U, N)                                                                  \
  static inline PC_OVL T pc_permute(T x, U src) {                                                         \
    S a[N], r[N];                                                                                         \
    uint from[N];                                                                                         \
    vstore##N(x, 0, a);                                                                                   \
    vstore##N(src, 0, from);                                                                              \
    for (uint j = 0u; j < N; ++j) r[j] = a[from[j]];                                                      \
    return vload##N(0, r);                                                                                \
  }
/* F, U: the float and uint vectors of N lanes, I the int one, PERMUTE_F and PERMUTE_I clang's vpermps and
 * vpermd builtins. */
#define PC_LANES_BY_PERMUTE(F, U, I, N, PERMUTE_F, PERMUTE_I)                                             \
  static inline PC_OVL F pc_permute(F x, U src) { return PERMUTE_F(x, as_##I(src)); }                    \
  static inline PC_OVL U pc_permute(U x, U src) { return as_##U(PERMUTE_I(as_##I(x), as_##I(src))); }     \
  static inline PC_OVL float pc_lane(F x, uint j) { return pc_permute(x, (U)(j)).s0; }
#define PC_LANES_BY_MEMORY(F, U, N)                                                                       \
  PC_PERMUTE_BY_MEMORY(F, float, U, N)                                                                    \
  PC_PERMUTE_BY_MEMORY(U, uint, U, N)                                                                     \
  PC_LANE_READ_BY_MEMORY(F, float, N)
#if defined(__clang__) && defined(__AVX2__)
PC_LANES_BY_PERMUTE(float8, uint8, int8, 8, __builtin_ia32_permvarsf256, __builtin_ia32_permvarsi256)
#else
PC_LANES_BY_MEMORY(float8, uint8, 8)
#endif
#if defined(__clang__) && defined(__AVX512F__)
PC_LANES_BY_PERMUTE(float16, uint16, int16, 16, __builtin_ia32_permvarsf512, __builtin_ia32_permvarsi512)
#else
PC_LANES_BY_MEMORY(float16, uint16, 16)
#endif
PC_LANE_READ_BY_MEMORY(uint8, uint, 8)
PC_LANE_READ_BY_MEMORY(uint16, uint, 16)
PC_LANE_WRITE(float8, float, 8)
PC_LANE_WRITE(uint8, uint, 8)
PC_LANE_WRITE(float16, float, 16)
PC_LANE_WRITE(uint16, uint, 16)
#undef PC_LANE_READ_BY_MEMORY
#undef PC_PERMUTE_BY_MEMORY
#undef PC_LANES_BY_PERMUTE
#undef PC_LANES_BY_MEMORY
#undef PC_LANE_WRITE

/* Functions of the lane code that PoCL would otherwise call rather than inline: a call passes their
 * vectors through memory. */
#define PC_LANE_INLINE static __attribute__((always_inline)) inline

/* ---- This program's lanes --------------------------------------------------------------------------- */
#ifndef PC_LANES
#define PC_LANES 1
#endif
#if PC_LANES == 1
typedef float LaneF;
typedef int LaneI;
typedef uint LaneU;
typedef lane3f Lane3;
/* The lanes from PC_LANES consecutive values and into them; a LaneF's (or LaneI's) bits as a LaneU. */
#define lane_load(p) (*(p))
#define lane_store(v, p) (*(p) = (v))
#define lane_as_u(x) as_uint(x)
#elif PC_LANES == 8
typedef float8 LaneF;
typedef int8 LaneI;
typedef uint8 LaneU;
typedef lane3f8 Lane3;
#define lane_load(p) vload8(0, p)
#define lane_store(v, p) vstore8(v, 0, p)
#define lane_as_u(x) as_uint8(x)
#elif PC_LANES == 16
typedef float16 LaneF;
typedef int16 LaneI;
typedef uint16 LaneU;
typedef lane3f16 Lane3;
#define lane_load(p) vload16(0, p)
#define lane_store(v, p) vstore16(v, 0, p)
#define lane_as_u(x) as_uint16(x)
#else
#error "PC_LANES: 1, 8 or 16 paths per work item"
#endif

/* PC_EACH_LANE(j, bits) { ... } runs the body once for each lane j set in bits (read once), lowest first,
 * skipping the others (for per-lane work with the one-lane code: textures, instances, the environment
 * map, and the render loop's tasks). */
#define PC_EACH_LANE(j, bits)                                                                             \
  for (uint pc_left_ = (bits), j = pc_lowest_bit(pc_left_); pc_left_ != 0u;                               \
       pc_left_ &= pc_left_ - 1u, j = pc_lowest_bit(pc_left_))

static inline uint lane_count(LaneI m) { return popcount(pc_lane_bits(m)); }

/* The pixels (or paths) a work item takes: W x PC_LANE_PIXELS with lanes, 1 with one (the host's item_pixels,
 * runtime/device_worker.cpp); and each lane's index j. */
#if PC_LANES > 1
#define PC_ITEM_PIXELS (PC_LANES * PC_LANE_PIXELS)
#else
#define PC_ITEM_PIXELS 1u
#endif
static inline LaneU lane_indices(void) {
  uint j_of[PC_LANES];
  for (uint j = 0u; j < PC_LANES; ++j) j_of[j] = j;
  return lane_load(j_of);
}

/* Lane src[j] of v in each lane j (pc_permute by component). */
static inline Lane3 lane3_permute(Lane3 v, LaneU src) {
  return lane3(pc_permute(v.x, src), pc_permute(v.y, src), pc_permute(v.z, src));
}

/* The first lane set in m (m must have one). */
static inline uint lane_first(LaneI m) {
  return pc_lowest_bit(pc_lane_bits(m));
}

/* index where m is set, the first set lane's elsewhere: an index at which a gather may read for every
 * lane (each read is of a valid element). */
static inline LaneU lane_safe_index(LaneU index, LaneI m) { return select((LaneU)(pc_lane(index, lane_first(m))), index, m); }

/* base[index * stride] of every lane (a gather): a vector built from PC_LANES loads in registers (loads
 * stored to a private array and read back as one vector wait for every store to reach the cache). Every
 * index must be valid (lane_safe_index). A field of an array of structs is (PC_FIELD_F(array, member),
 * index): the member's first word of element 0 and the struct's size in words; PC_FIELD_AT(array, member, k)
 * its word k (a component of a vector member). */
#define PC_FIELD_F(array, member) PC_FIELD_AT(array, member, 0)
#define PC_FIELD_AT(array, member, k) (__global const float*)&(array)->member + (k), (uint)(sizeof(*(array)) / 4u)
#define PC_FIELD_U(array, member) PC_FIELD_U_AT(array, member, 0)
#define PC_FIELD_U_AT(array, member, k) (__global const uint*)&(array)->member + (k), (uint)(sizeof(*(array)) / 4u)
#if PC_LANES == 1
PC_LANE_INLINE float lane_gather_float(__global const float* base, uint stride, uint index) { return base[index * stride]; }
PC_LANE_INLINE uint lane_gather_uint(__global const uint* base, uint stride, uint index) { return base[index * stride]; }
#elif PC_LANES == 8
PC_LANE_INLINE float8 lane_gather_float(__global const float* base, uint stride, uint8 index) {
  uint8 o = index * stride;
  return (float8)(base[o.s0], base[o.s1], base[o.s2], base[o.s3], base[o.s4], base[o.s5], base[o.s6], base[o.s7]);
}
PC_LANE_INLINE uint8 lane_gather_uint(__global const uint* base, uint stride, uint8 index) {
  uint8 o = index * stride;
  return (uint8)(base[o.s0], base[o.s1], base[o.s2], base[o.s3], base[o.s4], base[o.s5], base[o.s6], base[o.s7]);
}
#else
PC_LANE_INLINE float16 lane_gather_float(__global const float* base, uint stride, uint16 index) {
  uint16 o = index * stride;
  return (float16)(base[o.s0], base[o.s1], base[o.s2], base[o.s3], base[o.s4], base[o.s5], base[o.s6], base[o.s7],
    base[o.s8], base[o.s9], base[o.sa], base[o.sb], base[o.sc], base[o.sd], base[o.se], base[o.sf]);
}
PC_LANE_INLINE uint16 lane_gather_uint(__global const uint* base, uint stride, uint16 index) {
  uint16 o = index * stride;
  return (uint16)(base[o.s0], base[o.s1], base[o.s2], base[o.s3], base[o.s4], base[o.s5], base[o.s6], base[o.s7],
    base[o.s8], base[o.s9], base[o.sa], base[o.sb], base[o.sc], base[o.sd], base[o.se], base[o.sf]);
}
#endif

/* The float4 at base[index * stride] of every lane (a float4 member of an array of structs:
 * PC_FIELD_F4(array, member), index) as its xyz and w: one 16-byte load per lane and a transpose by
 * shuffles, where four lane_gather_float are a load and an insert per lane and word. Every index must be
 * valid (lane_safe_index). */
#define PC_FIELD_F4(array, member) (__global const float4*)&(array)->member, (uint)(sizeof(*(array)) / 16u)
#if PC_LANES == 1
PC_LANE_INLINE void lane_gather4(__global const float4* base, uint stride, uint index, Lane3* xyz, float* w) {
  float4 v = base[index * stride];
  *xyz = v.xyz;
  *w = v.w;
}
#elif PC_LANES == 8
PC_LANE_INLINE void lane_gather4(__global const float4* base, uint stride, uint8 index, Lane3* xyz, float8* w) {
  uint8 o = index * stride;
  /* r0 .. r3: the float4s of lanes 0 1, 2 3, 4 5, 6 7 */
  float8 r0 = (float8)(base[o.s0], base[o.s1]), r1 = (float8)(base[o.s2], base[o.s3]);
  float8 r2 = (float8)(base[o.s4], base[o.s5]), r3 = (float8)(base[o.s6], base[o.s7]);
  /* x and y, z and w of lanes 0-3 (from r0 r1) and 4-7 (r2 r3) */
  uint8 xy = (uint8)(0u, 4u, 8u, 12u, 1u, 5u, 9u, 13u), zw = xy + 2u;
  float8 xy_lo = shuffle2(r0, r1, xy), zw_lo = shuffle2(r0, r1, zw);
  float8 xy_hi = shuffle2(r2, r3, xy), zw_hi = shuffle2(r2, r3, zw);
  uint8 first = (uint8)(0u, 1u, 2u, 3u, 8u, 9u, 10u, 11u), second = first + 4u;
  *xyz = lane3(shuffle2(xy_lo, xy_hi, first), shuffle2(xy_lo, xy_hi, second), shuffle2(zw_lo, zw_hi, first));
  *w = shuffle2(zw_lo, zw_hi, second);
}
#else
PC_LANE_INLINE void lane_gather4(__global const float4* base, uint stride, uint16 index, Lane3* xyz, float16* w) {
  uint16 o = index * stride;
  /* r0 .. r3: the float4s of lanes 0-3, 4-7, 8-11, 12-15 */
  float16 r0 = (float16)(base[o.s0], base[o.s1], base[o.s2], base[o.s3]);
  float16 r1 = (float16)(base[o.s4], base[o.s5], base[o.s6], base[o.s7]);
  float16 r2 = (float16)(base[o.s8], base[o.s9], base[o.sa], base[o.sb]);
  float16 r3 = (float16)(base[o.sc], base[o.sd], base[o.se], base[o.sf]);
  /* x and y, z and w of lanes 0-7 (from r0 r1) and 8-15 (r2 r3) */
  uint16 xy = (uint16)(0u, 4u, 8u, 12u, 16u, 20u, 24u, 28u, 1u, 5u, 9u, 13u, 17u, 21u, 25u, 29u), zw = xy + 2u;
  float16 xy_lo = shuffle2(r0, r1, xy), zw_lo = shuffle2(r0, r1, zw);
  float16 xy_hi = shuffle2(r2, r3, xy), zw_hi = shuffle2(r2, r3, zw);
  uint16 first = (uint16)(0u, 1u, 2u, 3u, 4u, 5u, 6u, 7u, 16u, 17u, 18u, 19u, 20u, 21u, 22u, 23u), second = first + 8u;
  *xyz = lane3(shuffle2(xy_lo, xy_hi, first), shuffle2(xy_lo, xy_hi, second), shuffle2(zw_lo, zw_hi, first));
  *w = shuffle2(zw_lo, zw_hi, second);
}
#endif

/* The lanes of m grouped by index, when the lanes hold at most PC_LANE_GROUPS distinct indices (the light
 * each lane chose: a scene has few; the primitive it samples): a gather over the groups is a load and a
 * select per group instead of a load and an insert per lane. Lanes outside m join the first group
 * (lane_safe_index). m must have a lane. */
#define PC_LANE_GROUPS 4
typedef struct {
  LaneU index;                   /* lane_safe_index(index, m) */
  uint count;                    /* groups, or PC_INVALID for more than PC_LANE_GROUPS */
  uint value[PC_LANE_GROUPS];    /* each group's index */
  LaneI same[PC_LANE_GROUPS];    /* each group's lanes */
} LaneGroups;

PC_LANE_INLINE void lane_groups(LaneU index, LaneI m, LaneGroups* g) {
#if PC_LANES == 1
  /* One group: constants that reduce each group gather to its one load. */
  g->index = g->value[0] = index;
  g->same[0] = 1;
  g->count = 1u;
#else
  g->index = lane_safe_index(index, m);
  g->count = 0u;
  for (uint left = pc_lane_bits(m); left != 0u; ++g->count) {
    if (g->count == PC_LANE_GROUPS) {
      g->count = PC_INVALID;
      return;
    }
    uint v = pc_lane(g->index, pc_lowest_bit(left));
    g->value[g->count] = v;
    g->same[g->count] = g->index == v;
    left &= ~pc_lane_bits(g->same[g->count]);
  }
#endif
}

/* lane_gather_float and lane_gather_uint at the indices of g. */
#define PC_GROUP_GATHER(S, L)                                                                             \
  PC_LANE_INLINE L lane_group_gather_##S(__global const S* base, uint stride, const LaneGroups* g) {      \
    if (g->count == PC_INVALID) return lane_gather_##S(base, stride, g->index);                          \
    L r = (L)(base[g->value[0] * stride]);                                                                \
    for (uint k = 1u; k < g->count; ++k) r = select(r, (L)(base[g->value[k] * stride]), g->same[k]);      \
    return r;                                                                                             \
  }
PC_GROUP_GATHER(float, LaneF)
PC_GROUP_GATHER(uint, LaneU)
#undef PC_GROUP_GATHER
#define lane_group_gather3(...) PC_GROUP_GATHER3_(__VA_ARGS__)
#define PC_GROUP_GATHER3_(base, stride, g)                                                               \
  lane3(lane_group_gather_float((base), stride, g), lane_group_gather_float((base) + 1, stride, g),       \
        lane_group_gather_float((base) + 2, stride, g))

/* Lane3 arithmetic, component by component: each is the float3 operation of one lane. */
static inline Lane3 lane3_splat(float3 v) { return lane3((LaneF)(v.x), (LaneF)(v.y), (LaneF)(v.z)); }
static inline Lane3 lane3_add(Lane3 a, Lane3 b) { return lane3(a.x + b.x, a.y + b.y, a.z + b.z); }
static inline Lane3 lane3_sub(Lane3 a, Lane3 b) { return lane3(a.x - b.x, a.y - b.y, a.z - b.z); }
static inline Lane3 lane3_mul(Lane3 a, Lane3 b) { return lane3(a.x * b.x, a.y * b.y, a.z * b.z); }
static inline Lane3 lane3_scale(Lane3 a, LaneF s) { return lane3(a.x * s, a.y * s, a.z * s); }
static inline Lane3 lane3_div(Lane3 a, LaneF s) { return lane3(a.x / s, a.y / s, a.z / s); }
static inline Lane3 lane3_neg(Lane3 a) { return lane3(-a.x, -a.y, -a.z); }
static inline Lane3 lane3_abs(Lane3 a) { return lane3(fabs(a.x), fabs(a.y), fabs(a.z)); }
static inline Lane3 lane3_select(Lane3 a, Lane3 b, LaneI m) {
  return lane3(select(a.x, b.x, m), select(a.y, b.y, m), select(a.z, b.z, m));
}
static inline LaneI lane3_any_positive(Lane3 a) { return (a.x > 0.0f) | (a.y > 0.0f) | (a.z > 0.0f); }
static inline LaneF lane3_max_component(Lane3 a) { return fmax(a.x, fmax(a.y, a.z)); }

/* Lane j of a Lane3 as a float3, and a Lane3 with lane j replaced. */
static inline float3 lane3_at(Lane3 a, uint j) { return (float3)(pc_lane(a.x, j), pc_lane(a.y, j), pc_lane(a.z, j)); }
static inline Lane3 lane3_with(Lane3 a, uint j, float3 v) {
  return lane3(pc_with_lane(a.x, j, v.x), pc_with_lane(a.y, j, v.y), pc_with_lane(a.z, j, v.z));
}

#endif
