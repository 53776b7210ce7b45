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

/* Sobol dimensions 1-3: Joe and Kuo's direction numbers for their dimensions 2-4 (primitive polynomials
 * x + 1, x^2 + x + 1, x^3 + x + 1, initial m = {1}, {1, 3}, {1, 3, 1}), four per PC_SOBOL_NIBBLE, which
 * turns them into the XORs of every subset: entry [d][n][v] is the XOR of the direction numbers of bits
 * 4n .. 4n + 3 set in v. A 32-bit index then takes eight lookups instead of 32 conditional XORs (that loop
 * made the sobol sampler 3x slower than independent). Dimension 0 is the bit reversal of the index.
 * tests/sampler_test.cpp checks the tables against the direction numbers computed from the polynomials. */
#define PC_SOBOL_NIBBLE(a, b, c, d)                                                                     \
  {0u, a, b, a ^ b, c, a ^ c, b ^ c, a ^ b ^ c, d, a ^ d, b ^ d, a ^ b ^ d, c ^ d, a ^ c ^ d, b ^ c ^ d, \
   a ^ b ^ c ^ d}
__constant uint kSobolNibbles[3][8][16] = {
  {
    PC_SOBOL_NIBBLE(0x80000000u, 0xc0000000u, 0xa0000000u, 0xf0000000u),
    PC_SOBOL_NIBBLE(0x88000000u, 0xcc000000u, 0xaa000000u, 0xff000000u),
    PC_SOBOL_NIBBLE(0x80800000u, 0xc0c00000u, 0xa0a00000u, 0xf0f00000u),
    PC_SOBOL_NIBBLE(0x88880000u, 0xcccc0000u, 0xaaaa0000u, 0xffff0000u),
    PC_SOBOL_NIBBLE(0x80008000u, 0xc000c000u, 0xa000a000u, 0xf000f000u),
    PC_SOBOL_NIBBLE(0x88008800u, 0xcc00cc00u, 0xaa00aa00u, 0xff00ff00u),
    PC_SOBOL_NIBBLE(0x80808080u, 0xc0c0c0c0u, 0xa0a0a0a0u, 0xf0f0f0f0u),
    PC_SOBOL_NIBBLE(0x88888888u, 0xccccccccu, 0xaaaaaaaau, 0xffffffffu)},
  {
    PC_SOBOL_NIBBLE(0x80000000u, 0xc0000000u, 0x60000000u, 0x90000000u),
    PC_SOBOL_NIBBLE(0xe8000000u, 0x5c000000u, 0x8e000000u, 0xc5000000u),
    PC_SOBOL_NIBBLE(0x68800000u, 0x9cc00000u, 0xee600000u, 0x55900000u),
    PC_SOBOL_NIBBLE(0x80680000u, 0xc09c0000u, 0x60ee0000u, 0x90550000u),
    PC_SOBOL_NIBBLE(0xe8808000u, 0x5cc0c000u, 0x8e606000u, 0xc5909000u),
    PC_SOBOL_NIBBLE(0x6868e800u, 0x9c9c5c00u, 0xeeee8e00u, 0x5555c500u),
    PC_SOBOL_NIBBLE(0x8000e880u, 0xc0005cc0u, 0x60008e60u, 0x9000c590u),
    PC_SOBOL_NIBBLE(0xe8006868u, 0x5c009c9cu, 0x8e00eeeeu, 0xc5005555u)},
  {
    PC_SOBOL_NIBBLE(0x80000000u, 0xc0000000u, 0x20000000u, 0x50000000u),
    PC_SOBOL_NIBBLE(0xf8000000u, 0x74000000u, 0xa2000000u, 0x93000000u),
    PC_SOBOL_NIBBLE(0xd8800000u, 0x25400000u, 0x59e00000u, 0xe6d00000u),
    PC_SOBOL_NIBBLE(0x78080000u, 0xb40c0000u, 0x82020000u, 0xc3050000u),
    PC_SOBOL_NIBBLE(0x208f8000u, 0x51474000u, 0xfbea2000u, 0x75d93000u),
    PC_SOBOL_NIBBLE(0xa0858800u, 0x914e5400u, 0xdbe79e00u, 0x25db6d00u),
    PC_SOBOL_NIBBLE(0x58800080u, 0xe54000c0u, 0x79e00020u, 0xb6d00050u),
    PC_SOBOL_NIBBLE(0x800800f8u, 0xc00c0074u, 0x200200a2u, 0x50050093u)}};
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
inline PC_OVL uint pc_gather_(__constant const uint* a, uint i) { return a[i]; }
inline PC_OVL uint8 pc_gather_(__constant const uint* a, uint8 i) { return (uint8)(a[i.s0], a[i.s1], a[i.s2], a[i.s3], a[i.s4], a[i.s5], a[i.s6], a[i.s7]); }
inline PC_OVL uint16 pc_gather_(__constant const uint* a, uint16 i) {
  return (uint16)(a[i.s0], a[i.s1], a[i.s2], a[i.s3], a[i.s4], a[i.s5], a[i.s6], a[i.s7],
    a[i.s8], a[i.s9], a[i.sa], a[i.sb], a[i.sc], a[i.sd], a[i.se], a[i.sf]);
}

/* The XOR of the direction numbers of the four bits of index & 15 (a row of kSobolNibbles): one table
 * load for one lane; for 8 or 16 lanes four selects of the row's single-bit entries, since a gather of 8
 * or 16 loads costs more than the arithmetic. */
inline PC_OVL uint pc_sobol_nibble_(__constant const uint* row, uint index) { return row[index & 15u]; }
#define PC_SOBOL_NIBBLE_LANES(U)                                                                          \
  inline PC_OVL U pc_sobol_nibble_(__constant const uint* row, U index) {                                \
    return select((U)(0u), (U)(row[1]), (index & 1u) != 0u) ^ select((U)(0u), (U)(row[2]), (index & 2u) != 0u) ^ \
           select((U)(0u), (U)(row[4]), (index & 4u) != 0u) ^ select((U)(0u), (U)(row[8]), (index & 8u) != 0u); \
  }
PC_SOBOL_NIBBLE_LANES(uint8)
PC_SOBOL_NIBBLE_LANES(uint16)
#undef PC_SOBOL_NIBBLE_LANES

#define PC_SAMPLER_LANES(U, I, F, N)                                                                       \
  /* pcg4d (Jarzynski and Olano, "Hash Functions for GPU Rendering", JCGT 2020) of four lane values. */   \
  inline PC_OVL void pcg4d_lanes(U* x, U* y, U* z, U* w) {                                                \
    U a = *x * 1664525u + 1013904223u, b = *y * 1664525u + 1013904223u;                                   \
    U c = *z * 1664525u + 1013904223u, d = *w * 1664525u + 1013904223u;                                   \
    a += b * d; b += c * a; c += a * b; d += b * c;                                                       \
    a ^= a >> 16u; b ^= b >> 16u; c ^= c >> 16u; d ^= d >> 16u;                                           \
    a += b * d; b += c * a; c += a * b; d += b * c;                                                       \
    *x = a; *y = b; *z = c; *w = d;                                                                       \
  }                                                                                                       \
  inline PC_OVL U hash_uint(U x) { /* lowbias32 (Wellons) */                                              \
    x ^= x >> 16u;                                                                                        \
    x *= 0x7feb352du;                                                                                     \
    x ^= x >> 15u;                                                                                        \
    x *= 0x846ca68bu;                                                                                     \
    x ^= x >> 16u;                                                                                        \
    return x;                                                                                             \
  }                                                                                                       \
  inline PC_OVL U hash4(U a, U b, U c, U d) {                                                             \
    pcg4d_lanes(&a, &b, &c, &d);                                                                          \
    return a;                                                                                             \
  }                                                                                                       \
  inline PC_OVL F uint_to_unit(U x) { return convert_float##N(x >> 8u) * 0x1.0p-24f; }                    \
  inline PC_OVL U reverse_bits(U x) {                                                                     \
    x = ((x >> 1u) & 0x55555555u) | ((x & 0x55555555u) << 1u);                                            \
    x = ((x >> 2u) & 0x33333333u) | ((x & 0x33333333u) << 2u);                                            \
    x = ((x >> 4u) & 0x0f0f0f0fu) | ((x & 0x0f0f0f0fu) << 4u);                                            \
    x = ((x >> 8u) & 0x00ff00ffu) | ((x & 0x00ff00ffu) << 8u);                                            \
    return (x >> 16u) | (x << 16u);                                                                       \
  }                                                                                                       \
  /* Laine-Karras style permutation with Burley's constants: an Owen scramble of the reversed bits. */    \
  inline PC_OVL U nested_uniform_scramble(U x, U seed) {                                                  \
    x = reverse_bits(x);                                                                                  \
    x += seed;                                                                                            \
    x ^= x * 0x6c50b47cu;                                                                                 \
    x ^= x * 0xb82f1e52u;                                                                                 \
    x ^= x * 0xc7afe638u;                                                                                 \
    x ^= x * 0x8d22f6e6u;                                                                                 \
    return reverse_bits(x);                                                                               \
  }                                                                                                       \
  /* Sobol dimension dim in 1..3 of a 32-bit index, as bits. */                                           \
  inline PC_OVL U sobol_bits(U index, uint dim) {                                                         \
    U x = (U)(0u);                                                                                        \
    for (uint n = 0u; n < 8u; ++n) x ^= pc_sobol_nibble_(&kSobolNibbles[dim - 1u][n][0], index >> (4u * n)); \
    return x;                                                                                             \
  }                                                                                                       \
  /* A random permutation of [0, n): Kensler's hashed bijection of the next power of two, cycle-walked    \
   * into [0, n), then rotated. The rotation uses a second hash: Kensler's original rotation by p itself  \
   * is correlated with the bijection and made the marginal of small permutations non-uniform (a          \
   * measurable bias of Owen-scrambled Halton at low spp). */                                             \
  inline PC_OVL U permute_index(U i, U n, U p) {                                                          \
    U w = n - 1u;                                                                                         \
    w |= w >> 1u; w |= w >> 2u; w |= w >> 4u; w |= w >> 8u; w |= w >> 16u;                               \
    I walking = (I)(-1);                                                                                  \
    do {                                                                                                  \
      U j = i;                                                                                            \
      j ^= p; j *= 0xe170893du; j ^= p >> 16u; j ^= (j & w) >> 4u; j ^= p >> 8u; j *= 0x0929eb3fu;        \
      j ^= p >> 23u; j ^= (j & w) >> 1u; j *= 1u | p >> 27u; j *= 0x6935fa69u; j ^= (j & w) >> 11u;       \
      j *= 0x74dcb303u; j ^= (j & w) >> 2u; j *= 0x9e501cc3u; j ^= (j & w) >> 2u; j *= 0xc860a3dfu;       \
      j &= w; j ^= j >> 5u;                                                                               \
      i = select(i, j, walking);                                                                          \
      walking = walking & (j >= n);                                                                       \
    } while (pc_any_(walking));                                                                           \
    return (i + hash_uint(p ^ 0x68bc21ebu)) % n;                                                          \
  }                                                                                                       \
  /* One pair of stratified dimensions: the sample's stratum in an nx x ny grid of about spp, jittered. */\
  inline PC_OVL void stratified_pair(U pixel, U sample, uint seed, uint spp, U pair_id, F* x, F* y) {     \
    uint nx = max(1u, (uint)sqrt((float)spp)), ny = max(1u, spp / nx), n = nx * ny;                       \
    U h = hash4(pixel, pair_id, (U)(seed), (U)(0x5851f42du));                                             \
    F jx = uint_to_unit(hash4(pixel, sample, pair_id, (U)(seed ^ 0x2545f491u)));                          \
    F jy = uint_to_unit(hash4(sample, pixel, pair_id, (U)(seed ^ 0x9e3779b9u)));                          \
    U stratum = permute_index(sample % n, (U)(n), h);                                                     \
    *x = (convert_float##N(stratum % nx) + jx) / (float)nx;                                               \
    *y = (convert_float##N(stratum / nx) + jy) / (float)ny;                                               \
  }                                                                                                       \
  inline PC_OVL F owen_scrambled_radical_inverse(U base, U a, U hash) {                                   \
    F inv_base = 1.0f / convert_float##N(base), inv_base_m = (F)(1.0f);                                   \
    U reversed = (U)(0u), digit_count = (U)(0u);                                                          \
    /* Digits until they no longer change a float in [0, 1). */                                           \
    I active = (1.0f - inv_base_m < 1.0f) & (inv_base_m > 0x1.0p-24f);                                    \
    while (pc_any_(active)) {                                                                             \
      U next = a / base, digit = a - next * base;                                                         \
      /* Each node of the digit tree (the digits below it) permutes its digit with its own hash. */       \
      digit = permute_index(digit, base, hash_uint(hash ^ (reversed * 0x9e3779b9u + digit_count)));       \
      reversed = select(reversed, reversed * base + digit, active);                                       \
      inv_base_m = select(inv_base_m, inv_base_m * inv_base, active);                                     \
      digit_count = select(digit_count, digit_count + 1u, active);                                        \
      a = select(a, next, active);                                                                        \
      active = (1.0f - inv_base_m < 1.0f) & (inv_base_m > 0x1.0p-24f);                                    \
    }                                                                                                     \
    return fmin(inv_base_m * convert_float##N(reversed), 0x1.fffffep-1f);                                 \
  }                                                                                                       \
  /* Four uniform numbers in [0, 1) per lane, for dimensions 4 group .. 4 group + 3 of the lane's key     \
   * (pixel, sample, seed). */                                                                            \
  inline PC_OVL void sample4_lanes(__constant const SceneHeader* h, U pixel, U sample, uint seed, U group, \
                                   F* u0, F* u1, F* u2, F* u3) {                                          \
    if (h->sampler == PC_SAMPLER_STRATIFIED) {                                                            \
      stratified_pair(pixel, sample, seed, h->spp, 2u * group, u0, u1);                                   \
      stratified_pair(pixel, sample, seed, h->spp, 2u * group + 1u, u2, u3);                              \
      return;                                                                                             \
    }                                                                                                     \
    if (h->sampler == PC_SAMPLER_SOBOL) {                                                                 \
      U lane_seed = hash4(pixel, group, (U)(seed), (U)(0x68e31da4u));                                     \
      U index = nested_uniform_scramble(sample, lane_seed);                                               \
      *u0 = uint_to_unit(nested_uniform_scramble(reverse_bits(index), hash_uint(lane_seed ^ 0x1u)));      \
      *u1 = uint_to_unit(nested_uniform_scramble(sobol_bits(index, 1u), hash_uint(lane_seed ^ 0x2u)));    \
      *u2 = uint_to_unit(nested_uniform_scramble(sobol_bits(index, 2u), hash_uint(lane_seed ^ 0x3u)));    \
      *u3 = uint_to_unit(nested_uniform_scramble(sobol_bits(index, 3u), hash_uint(lane_seed ^ 0x4u)));    \
      return;                                                                                             \
    }                                                                                                     \
    /* Halton for the first 64 dimensions; beyond them, and for the independent sampler, hashed numbers. */\
    I halton = (I)(h->sampler == PC_SAMPLER_HALTON ? -1 : 0) & (4u * group + 3u < PC_HALTON_DIMENSIONS);  \
    F x = (F)(0.0f), y = (F)(0.0f), z = (F)(0.0f), w = (F)(0.0f);                                         \
    if (pc_any_(halton)) {                                                                                \
      U first = select((U)(0u), 4u * group, halton); /* lanes past the table read its start, unused */   \
      U base_hash = hash4(pixel, (U)(seed), (U)(0xb5297a4du), (U)(0u));                                   \
      x = owen_scrambled_radical_inverse(pc_gather_(kPrimes, first), sample, hash_uint(base_hash ^ first)); \
      y = owen_scrambled_radical_inverse(pc_gather_(kPrimes, first + 1u), sample,                         \
                                         hash_uint(base_hash ^ (first + 1u)));                            \
      z = owen_scrambled_radical_inverse(pc_gather_(kPrimes, first + 2u), sample,                         \
                                         hash_uint(base_hash ^ (first + 2u)));                            \
      w = owen_scrambled_radical_inverse(pc_gather_(kPrimes, first + 3u), sample,                         \
                                         hash_uint(base_hash ^ (first + 3u)));                            \
    }                                                                                                     \
    if (pc_any_(!halton)) {                                                           \
      U a = pixel, b = sample, c = group, d = (U)(seed);                                                  \
      pcg4d_lanes(&a, &b, &c, &d);                                                                        \
      a ^= 0x9e3779b9u; b ^= 0x85ebca6bu; c ^= 0xc2b2ae35u; d ^= 0x27d4eb2fu;                              \
      pcg4d_lanes(&a, &b, &c, &d);                                                                        \
      x = select(uint_to_unit(a), x, halton);                                                             \
      y = select(uint_to_unit(b), y, halton);                                                             \
      z = select(uint_to_unit(c), z, halton);                                                             \
      w = select(uint_to_unit(d), w, halton);                                                             \
    }                                                                                                     \
    *u0 = x; *u1 = y; *u2 = z; *u3 = w;                                                                   \
  }
PC_SAMPLER_LANES(uint, int, float, )
PC_SAMPLER_LANES(uint8, int8, float8, 8)
PC_SAMPLER_LANES(uint16, int16, float16, 16)
#undef PC_SAMPLER_LANES

/* pcg4d of the four components of v. */
inline uint4 pcg4d(uint4 v) {
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
#define PC_DIM_LIGHT(depth) (1u + 2u * (depth))
#define PC_DIM_BSDF(depth) (2u + 2u * (depth))
/* The rays of a camera path, numbered for their cut-out seeds (cutout.cl): the camera ray, then per
 * scattering event `depth` its shadow ray and the ray leaving it. */
#define PC_RAY_CAMERA 0u
#define PC_RAY_SHADOW(depth) (2u * (depth) + 1u)
#define PC_RAY_NEXT(depth) (2u * (depth) + 2u)

/* Four uniform numbers in [0, 1) for dimensions 4 group .. 4 group + 3 of one key. */
inline float4 sample4(__constant const SceneHeader* h, SampleKey key, uint group) {
  float x, y, z, w;
  sample4_lanes(h, key.pixel, key.sample, key.seed, group, &x, &y, &z, &w);
  return (float4)(x, y, z, w);
}

#endif
