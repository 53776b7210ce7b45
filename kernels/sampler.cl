/* Samplers: every value is a pure function of (pixel, sample index, dimension, seed), so renders are
 * deterministic and any prefix of samples is usable. Dimensions come in groups of four (sample4).
 *   independent: hashed random numbers.
 *   stratified:  each pair of dimensions jittered in a grid of about spp strata, the strata visited in a
 *                per-pixel random order (Kensler's permutation), so every sample is still uniform alone.
 *   sobol:       4-D Sobol points, Owen-scrambled by hashing (Burley 2020, "Practical Hash-based Owen
 *                Scrambling"), with the sample index shuffled per pixel and per group of dimensions.
 *   halton:      radical inverses in the first 64 prime bases with per-digit hashed permutations
 *                (Owen-scrambled Halton as in pbrt-v4); dimensions past 64 fall back to independent. */
#ifndef PATHCL_SAMPLER_CL
#define PATHCL_SAMPLER_CL

#include "exact_math.cl"
#include "rng.cl"

#define PC_HALTON_DIMENSIONS 64

/* Sobol dimensions 2 and 3: Joe and Kuo's direction numbers for their dimensions 3 and 4 (primitive
 * polynomials x^2 + x + 1 and x^3 + x + 1, initial m = {1, 3} and {1, 3, 1}), bit-reversed (the scramble
 * takes the points' reversed bits), four per PC_SOBOL_NIBBLE, which turns them into the XORs of every
 * subset: entry [d][n][v] is the XOR of the direction numbers of bits 4n .. 4n + 3 set in v. A 32-bit index
 * then takes eight lookups instead of 32 conditional XORs (that loop made the sobol sampler 3x slower than
 * independent). Dimension 0 is the bit reversal of the index, dimension 1 (x + 1) needs no table
 * (sobol1_reversed). tests/sampler_test.cpp checks all three against the direction numbers computed from
 * the polynomials. */
#define PC_SOBOL_NIBBLE(a, b, c, d)                                                                     \
  {0u, a, b, a ^ b, c, a ^ c, b ^ c, a ^ b ^ c, d, a ^ d, b ^ d, a ^ b ^ d, c ^ d, a ^ c ^ d, b ^ c ^ d, \
   a ^ b ^ c ^ d}
__constant uint kSobolNibbles[2][8][16] = {
  {
    PC_SOBOL_NIBBLE(0x00000001u, 0x00000003u, 0x00000006u, 0x00000009u),
    PC_SOBOL_NIBBLE(0x00000017u, 0x0000003au, 0x00000071u, 0x000000a3u),
    PC_SOBOL_NIBBLE(0x00000116u, 0x00000339u, 0x00000677u, 0x000009aau),
    PC_SOBOL_NIBBLE(0x00001601u, 0x00003903u, 0x00007706u, 0x0000aa09u),
    PC_SOBOL_NIBBLE(0x00010117u, 0x0003033au, 0x00060671u, 0x000909a3u),
    PC_SOBOL_NIBBLE(0x00171616u, 0x003a3939u, 0x00717777u, 0x00a3aaaau),
    PC_SOBOL_NIBBLE(0x01170001u, 0x033a0003u, 0x06710006u, 0x09a30009u),
    PC_SOBOL_NIBBLE(0x16160017u, 0x3939003au, 0x77770071u, 0xaaaa00a3u)},
  {
    PC_SOBOL_NIBBLE(0x00000001u, 0x00000003u, 0x00000004u, 0x0000000au),
    PC_SOBOL_NIBBLE(0x0000001fu, 0x0000002eu, 0x00000045u, 0x000000c9u),
    PC_SOBOL_NIBBLE(0x0000011bu, 0x000002a4u, 0x0000079au, 0x00000b67u),
    PC_SOBOL_NIBBLE(0x0000101eu, 0x0000302du, 0x00004041u, 0x0000a0c3u),
    PC_SOBOL_NIBBLE(0x0001f104u, 0x0002e28au, 0x000457dfu, 0x000c9baeu),
    PC_SOBOL_NIBBLE(0x0011a105u, 0x002a7289u, 0x0079e7dbu, 0x00b6dba4u),
    PC_SOBOL_NIBBLE(0x0100011au, 0x030002a7u, 0x0400079eu, 0x0a000b6du),
    PC_SOBOL_NIBBLE(0x1f001001u, 0x2e003003u, 0x45004004u, 0xc900a00au)}};
#undef PC_SOBOL_NIBBLE

__constant uint kPrimes[PC_HALTON_DIMENSIONS] = {2, 3, 5, 7, 11, 13, 17, 19, 23, 29, 31, 37, 41, 43, 47, 53, 59, 61, 67, 71, 73, 79, 83, 89, 97, 101, 103, 107, 109, 113, 127, 131, 137, 139, 149, 151, 157, 163, 167, 173, 179, 181, 191, 193, 197, 199, 211, 223, 227, 229, 233, 239, 241, 251, 257, 263, 269, 271, 277, 281, 283, 293, 307, 311};

/* ---- The samplers over lanes ------------------------------------------------------------------------
 * Each function is written once, as a macro over the lane types: U (uint for one lane, uint8 or uint16
 * for 8 or 16 lanes of a lane-generic kernel, issue 15), its int type I, float type F and suffix N. Every
 * lane does exactly the integer and IEEE operations of the one-lane call, so the numbers are the same bits
 * at every lane width (tests/sampler_test.cpp, LanesGiveTheOneLaneBits). Loops whose trip count differs
 * per lane (cycle walking, radical-inverse digits) run while any lane is active and keep the finished
 * lanes' values by select(); masks follow exact_math.cl (1 for one lane, -1 for vectors; pc_any_). */

/* Lane j of a uint table lookup a[i]: a vector built from one load per lane (a private array read back as
 * one vector waits for every store to reach the cache). */
static inline PC_OVL uint pc_gather_(__constant const uint* a, uint i) { return a[i]; }
static inline PC_OVL uint8 pc_gather_(__constant const uint* a, uint8 i) { return (uint8)(a[i.s0], a[i.s1], a[i.s2], a[i.s3], a[i.s4], a[i.s5], a[i.s6], a[i.s7]); }
static inline PC_OVL uint16 pc_gather_(__constant const uint* a, uint16 i) {
  return (uint16)(a[i.s0], a[i.s1], a[i.s2], a[i.s3], a[i.s4], a[i.s5], a[i.s6], a[i.s7],
    a[i.s8], a[i.s9], a[i.sa], a[i.sb], a[i.sc], a[i.sd], a[i.se], a[i.sf]);
}

#define PC_LANE_W 1
#include "templates/sampler.cl"
#define PC_LANE_W 8
#include "templates/sampler.cl"
#define PC_LANE_W 16
#include "templates/sampler.cl"

/* pcg4d of the four components of v. */
static inline uint4 pcg4d(uint4 v) {
  uint x = v.x, y = v.y, z = v.z, w = v.w;
  pcg4d_lanes(&x, &y, &z, &w);
  return (uint4)(x, y, z, w);
}

/* The groups of a camera path's sample dimensions (the path integrator's, BDPT's camera subpath's and the
 * AOV pass's, so that all three take the same camera rays and BSDF choices): the camera ray (xy: pixel
 * position, zw: lens point), then per scattering event `depth` the light sample (xyz: the light and the
 * point on it; w: Russian roulette) and the BSDF sample (xyz: direction and lobe). Light paths take their
 * groups above every camera path's (light_path.cl, PC_LT_*). */
#define PC_DIM_CAMERA 0u
/* The first group of a light path's (light_path.cl's PC_LT_*): above every camera path's. */
static inline uint light_group_base(__constant const SceneHeader* h) { return max(64u, 2u * h->max_depth + 3u); }
#define PC_DIM_LIGHT(depth) (1u + 2u * (depth))
#define PC_DIM_BSDF(depth) (2u + 2u * (depth))
/* The rays of a camera path, numbered for their cut-out seeds (cutout.cl): the camera ray, then per
 * scattering event `depth` its shadow ray and the ray leaving it. */
#define PC_RAY_CAMERA 0u
#define PC_RAY_SHADOW(depth) (2u * (depth) + 1u)
#define PC_RAY_NEXT(depth) (2u * (depth) + 2u)

#ifdef PC_MLT
/* Metropolis (mlt.cl): a state holds four numbers for each group a BDPT sample of max_depth D reads, in
 * slots: the camera subpath's groups 0 .. 2 D, the light subpath's light_group_base .. + 2 D + 1, then the
 * strategy's (group PC_MLT_STRATEGY_GROUP, the one after the light subpath's). */
static inline uint mlt_slots(__constant const SceneHeader* h) { return 4u * h->max_depth + 4u; }
#define PC_MLT_STRATEGY_GROUP(h) (light_group_base(h) + 2u * (h)->max_depth + 2u)
static inline uint mlt_slot(__constant const SceneHeader* h, uint group) {
  uint base = light_group_base(h);
  if (group <= 2u * h->max_depth) return group;
  if (group >= base && group - base <= 2u * h->max_depth + 2u) return 2u * h->max_depth + 1u + (group - base);
  return PC_INVALID;
}

/* A state's numbers, mutated lazily (pbrt-v4's MLTSampler): a slot is brought to the current iteration
 * when read. Either fresh (every slot uniform from hash (a, b, its index): bootstrap candidates) or a
 * chain's step (a = chain, b = step): a large step takes uniform numbers from (a, b); a small step moves a
 * slot last changed n iterations ago by Kelemen's exponential mutation, its size times sqrt(n) (the n steps
 * it missed, as if each had moved it: a symmetric move all the same), after resetting it to its value at
 * the last accepted large step if it was last changed before it. The slots a step changes are kept to be
 * put back if the proposal is rejected (mlt_reject); iterations count accepted steps. */
typedef struct MltSampler {
  float* x;                 /* 4 per slot */
  uint* modified;           /* per slot: the iteration of its last change */
  float* backup;            /* 4 per slot: its numbers before this step changed them */
  uint* backup_modified;
  uint* changed;            /* the slots this step changed, changed_count of them */
  uint changed_count;
  uint iteration;           /* accepted steps (the step's: one more) */
  uint last_large;          /* the iteration of the last accepted large step, its step last_large_step */
  uint last_large_step;
  uint large;               /* this step is a large step */
  uint fresh;
  uint a, b, seed;
  float size;               /* a small step's largest move */
} MltSampler;

static inline float mlt_uniform(uint a, uint b, uint k, uint seed) { return uint_to_unit(hash4(a, b, k, seed ^ 0x70737321u)); }

/* Kelemen's mutation of one number: moved up or down by s2 2^(-4 u) (s2 = size, u uniform), wrapped into
 * [0, 1); 2^(-f) for the fraction f of 4 u is taken linear between its ends, 1 - f / 2. Any move of a
 * distribution that does not depend on x keeps the proposal symmetric; this one costs a multiplication
 * where the exponential (the exact one of exact_math.cl, for the same bits everywhere) was 8 % of a step. */
static inline float mlt_mutate(float x, float size, uint bits) {
  float f = (float)((bits >> 8u) & 0x3fffffu) * 0x1.0p-22f; /* 4 u = (bits >> 30) + f */
  float dv = ldexp(size * (1.0f - 0.5f * f), -(int)(bits >> 30u));
  float y = (bits & 1u) ? x + dv : x - dv;
  y -= floor(y);
  return y < 1.0f ? y : 0.0f;
}

/* Slot `slot`'s numbers uniform from hash (a, b). */
static inline void mlt_uniform_slot(MltSampler* m, uint slot, uint b) {
  for (uint k = 0; k < 4u; ++k) m->x[4u * slot + k] = mlt_uniform(m->a, b, 4u * slot + k, m->seed);
}

/* Slot `slot` at the sampler's iteration. */
static inline void mlt_ensure_ready(MltSampler* m, uint slot) {
  if (m->modified[slot] == m->iteration) return;
  if (!m->fresh) {
    for (uint k = 0; k < 4u; ++k) m->backup[4u * slot + k] = m->x[4u * slot + k];
    m->backup_modified[slot] = m->modified[slot];
    m->changed[m->changed_count++] = slot;
  }
  if (m->fresh || m->large) {
    mlt_uniform_slot(m, slot, m->b);
  } else {
    if (m->modified[slot] < m->last_large) {
      mlt_uniform_slot(m, slot, m->last_large_step);
      m->modified[slot] = m->last_large;
    }
    float size = m->size * sqrt((float)(m->iteration - m->modified[slot]));
    for (uint k = 0; k < 4u; ++k)
      m->x[4u * slot + k] = mlt_mutate(m->x[4u * slot + k], size, hash4(m->a, m->b, 4u * slot + k, m->seed ^ 0x6d757421u));
  }
  m->modified[slot] = m->iteration;
}

/* A rejected proposal: the slots it changed back as they were, and the iteration. */
static inline void mlt_reject(MltSampler* m) {
  for (uint j = 0; j < m->changed_count; ++j) {
    uint slot = m->changed[j];
    for (uint k = 0; k < 4u; ++k) m->x[4u * slot + k] = m->backup[4u * slot + k];
    m->modified[slot] = m->backup_modified[slot];
  }
  --m->iteration;
}

/* The pixel a state's image position u (its camera group's xy, in [0, 1)) lies in. */
static inline uint2 mlt_pixel(__constant const SceneHeader* h, float2 u) {
  float2 raster = u * (float2)((float)h->width, (float)h->height);
  return min(convert_uint2(raster), (uint2)(h->width - 1u, h->height - 1u));
}

/* Slot `slot`'s four numbers at the sampler's iteration. */
static inline float4 mlt_numbers(MltSampler* m, uint slot) {
  mlt_ensure_ready(m, slot);
  return vload4(slot, m->x);
}
#endif

/* Four uniform numbers in [0, 1) for dimensions 4 group .. 4 group + 3 of one key (a Metropolis chain's,
 * key.mlt set: its state's, the camera group's image position there the pixel's, within the pixel the state
 * takes; mlt's pixels' own samples, key.mlt 0: the render's sampler). */
static inline float4 sample4(__constant const SceneHeader* h, SampleKey key, uint group) {
#ifdef PC_MLT
  uint slot = key.mlt ? mlt_slot(h, group) : PC_INVALID;
  if (slot != PC_INVALID) {
    float4 u = mlt_numbers(key.mlt, slot);
    if (group == PC_DIM_CAMERA) u.xy = u.xy * (float2)((float)h->width, (float)h->height) - convert_float2(mlt_pixel(h, u.xy));
    return u;
  }
#endif
  float x, y, z, w;
  sample4_lanes(h, key.pixel, key.sample, key.seed, group, &x, &y, &z, &w);
  return (float4)(x, y, z, w);
}

#endif
