/* The samplers' lane functions: a template, included by sampler.cl once per lane width
 * PC_LANE_W (1, 8, 16) with templates/lane_width.h's types F, I, U and V3. */
#include "templates/lane_width.h"

/* pcg4d (Jarzynski and Olano, "Hash Functions for GPU Rendering", JCGT 2020) of four lane values. */
static inline PC_OVL void pcg4d_lanes(U* x, U* y, U* z, U* w) {
  U a = *x * 1664525u + 1013904223u, b = *y * 1664525u + 1013904223u;
  U c = *z * 1664525u + 1013904223u, d = *w * 1664525u + 1013904223u;
  a += b * d; b += c * a; c += a * b; d += b * c;
  a ^= a >> 16u; b ^= b >> 16u; c ^= c >> 16u; d ^= d >> 16u;
  a += b * d; b += c * a; c += a * b; d += b * c;
  *x = a; *y = b; *z = c; *w = d;
}
static inline PC_OVL U hash_uint(U x) { /* lowbias32 (Wellons) */
  x ^= x >> 16u;
  x *= 0x7feb352du;
  x ^= x >> 15u;
  x *= 0x846ca68bu;
  x ^= x >> 16u;
  return x;
}
static inline PC_OVL U hash4(U a, U b, U c, U d) {
  pcg4d_lanes(&a, &b, &c, &d);
  return a;
}
static inline PC_OVL F uint_to_unit(U x) { return convert_F(x >> 8u) * 0x1.0p-24f; }
static inline PC_OVL U reverse_bits(U x) {
  x = ((x >> 1u) & 0x55555555u) | ((x & 0x55555555u) << 1u);
  x = ((x >> 2u) & 0x33333333u) | ((x & 0x33333333u) << 2u);
  x = ((x >> 4u) & 0x0f0f0f0fu) | ((x & 0x0f0f0f0fu) << 4u);
  x = ((x >> 8u) & 0x00ff00ffu) | ((x & 0x00ff00ffu) << 8u);
  return (x >> 16u) | (x << 16u);
}
/* Laine-Karras style permutation with Burley's constants, of bits already reversed: nested uniform
 * (Owen) scrambling of x is reverse_bits(laine_karras_permutation(reverse_bits(x), seed)). */
static inline PC_OVL U laine_karras_permutation(U x, U seed) {
  x += seed;
  x ^= x * 0x6c50b47cu;
  x ^= x * 0xb82f1e52u;
  x ^= x * 0xc7afe638u;
  x ^= x * 0x8d22f6e6u;
  return x;
}
/* Sobol dimension 1 of a 32-bit index, bit-reversed. Its generator matrix is Pascal's triangle mod 2
 * (polynomial x + 1): direction number k has bit 31 - j set where C(k, j) is odd, that is (Lucas) where
 * j's bits are a subset of k's. So bit j of the reversed point is the XOR of the index's bits k whose bits
 * are a superset of j's: that transform takes one step per bit of j, not one per bit of the index. */
static inline PC_OVL U sobol1_reversed(U x) {
  x ^= (x >> 1u) & 0x55555555u;
  x ^= (x >> 2u) & 0x33333333u;
  x ^= (x >> 4u) & 0x0f0f0f0fu;
  x ^= (x >> 8u) & 0x00ff00ffu;
  x ^= x >> 16u;
  return x;
}
/* Sobol dimensions 2 and 3 of a 32-bit index, bit-reversed: eight table lookups each for one lane; for 8
 * or 16 lanes (a gather of 8 or 16 loads costs more than the arithmetic) the direction numbers of the
 * index's set bits, each bit's lane mask made once for both dimensions. */
static inline PC_OVL void sobol23_reversed(U index, U* x2, U* x3) {
  U a = (U)(0u), b = (U)(0u);
#if PC_LANE_W == 1
  for (uint n = 0u; n < 8u; ++n) {
    uint v = (index >> (4u * n)) & 15u;
    a ^= kSobolNibbles[0][n][v];
    b ^= kSobolNibbles[1][n][v];
  }
#else
#pragma unroll
  for (uint k = 0u; k < 32u; ++k) {
    U m = as_U(as_I(index << (31u - k)) >> 31); /* all ones where bit k is set */
    a ^= m & kSobolNibbles[0][k / 4u][1u << (k % 4u)];
    b ^= m & kSobolNibbles[1][k / 4u][1u << (k % 4u)];
  }
#endif
  *x2 = a;
  *x3 = b;
}
/* A random permutation of [0, n): Kensler's hashed bijection of the next power of two, cycle-walked
 * into [0, n), then rotated. The rotation uses a second hash: Kensler's original rotation by p itself
 * is correlated with the bijection and made the marginal of small permutations non-uniform (a
 * measurable bias of Owen-scrambled Halton at low spp). */
static inline PC_OVL U permute_index(U i, U n, U p) {
  U w = n - 1u;
  w |= w >> 1u; w |= w >> 2u; w |= w >> 4u; w |= w >> 8u; w |= w >> 16u;
  I walking = (I)(-1);
  do {
    U j = i;
    j ^= p; j *= 0xe170893du; j ^= p >> 16u; j ^= (j & w) >> 4u; j ^= p >> 8u; j *= 0x0929eb3fu;
    j ^= p >> 23u; j ^= (j & w) >> 1u; j *= 1u | p >> 27u; j *= 0x6935fa69u; j ^= (j & w) >> 11u;
    j *= 0x74dcb303u; j ^= (j & w) >> 2u; j *= 0x9e501cc3u; j ^= (j & w) >> 2u; j *= 0xc860a3dfu;
    j &= w; j ^= j >> 5u;
    i = select(i, j, walking);
    walking = walking & (j >= n);
  } while (pc_any_(walking));
  return (i + hash_uint(p ^ 0x68bc21ebu)) % n;
}
/* One pair of stratified dimensions: the sample's stratum in an nx x ny grid of about spp, jittered. */
static inline PC_OVL void stratified_pair(U pixel, U sample, uint seed, uint spp, U pair_id, F* x, F* y) {
  uint nx = max(1u, (uint)sqrt((float)spp)), ny = max(1u, spp / nx), n = nx * ny;
  U h = hash4(pixel, pair_id, (U)(seed), (U)(0x5851f42du));
  F jx = uint_to_unit(hash4(pixel, sample, pair_id, (U)(seed ^ 0x2545f491u)));
  F jy = uint_to_unit(hash4(sample, pixel, pair_id, (U)(seed ^ 0x9e3779b9u)));
  U stratum = permute_index(sample % n, (U)(n), h);
  *x = (convert_F(stratum % nx) + jx) / (float)nx;
  *y = (convert_F(stratum / nx) + jy) / (float)ny;
}
static inline PC_OVL F owen_scrambled_radical_inverse(U base, U a, U hash) {
  F inv_base = 1.0f / convert_F(base), inv_base_m = (F)(1.0f);
  U reversed = (U)(0u), digit_count = (U)(0u);
  /* Digits until they no longer change a float in [0, 1). */
  I active = (1.0f - inv_base_m < 1.0f) & (inv_base_m > 0x1.0p-24f);
  while (pc_any_(active)) {
    U next = a / base, digit = a - next * base;
    /* Each node of the digit tree (the digits below it) permutes its digit with its own hash. */
    digit = permute_index(digit, base, hash_uint(hash ^ (reversed * 0x9e3779b9u + digit_count)));
    reversed = select(reversed, reversed * base + digit, active);
    inv_base_m = select(inv_base_m, inv_base_m * inv_base, active);
    digit_count = select(digit_count, digit_count + 1u, active);
    a = select(a, next, active);
    active = (1.0f - inv_base_m < 1.0f) & (inv_base_m > 0x1.0p-24f);
  }
  return fmin(inv_base_m * convert_F(reversed), 0x1.fffffep-1f);
}
/* Four uniform numbers in [0, 1) per lane, for dimensions 4 group .. 4 group + 3 of the lane's key
 * (pixel, sample, seed). */
static inline PC_OVL void sample4_lanes(__constant const SceneHeader* h, U pixel, U sample, uint seed, U group,
                                        F* u0, F* u1, F* u2, F* u3) {
  if (h->sampler == PC_SAMPLER_STRATIFIED) {
    stratified_pair(pixel, sample, seed, h->spp, 2u * group, u0, u1);
    stratified_pair(pixel, sample, seed, h->spp, 2u * group + 1u, u2, u3);
    return;
  }
  if (h->sampler == PC_SAMPLER_SOBOL) {
    U lane_seed = hash4(pixel, group, (U)(seed), (U)(0x68e31da4u));
    /* The pixel's shuffled index: the sample's, nested-uniform scrambled. Each dimension's point is then
     * scrambled in turn; the scramble reads and writes reversed bits, which sobol1_reversed and
     * sobol23_reversed give directly, and dimension 0's point is the reversed index itself. */
    U index = reverse_bits(laine_karras_permutation(reverse_bits(sample), lane_seed)), x2, x3;
    sobol23_reversed(index, &x2, &x3);
    *u0 = uint_to_unit(reverse_bits(laine_karras_permutation(index, hash_uint(lane_seed ^ 0x1u))));
    *u1 = uint_to_unit(reverse_bits(laine_karras_permutation(sobol1_reversed(index), hash_uint(lane_seed ^ 0x2u))));
    *u2 = uint_to_unit(reverse_bits(laine_karras_permutation(x2, hash_uint(lane_seed ^ 0x3u))));
    *u3 = uint_to_unit(reverse_bits(laine_karras_permutation(x3, hash_uint(lane_seed ^ 0x4u))));
    return;
  }
  /* Halton for the first 64 dimensions; beyond them, and for the independent sampler, hashed numbers. */
  I halton = (I)(h->sampler == PC_SAMPLER_HALTON ? -1 : 0) & (4u * group + 3u < PC_HALTON_DIMENSIONS);
  F x = (F)(0.0f), y = (F)(0.0f), z = (F)(0.0f), w = (F)(0.0f);
  if (pc_any_(halton)) {
    U first = select((U)(0u), 4u * group, halton); /* lanes past the table read its start, unused */
    U base_hash = hash4(pixel, (U)(seed), (U)(0xb5297a4du), (U)(0u));
    x = owen_scrambled_radical_inverse(pc_gather_(kPrimes, first), sample, hash_uint(base_hash ^ first));
    y = owen_scrambled_radical_inverse(pc_gather_(kPrimes, first + 1u), sample,
                                       hash_uint(base_hash ^ (first + 1u)));
    z = owen_scrambled_radical_inverse(pc_gather_(kPrimes, first + 2u), sample,
                                       hash_uint(base_hash ^ (first + 2u)));
    w = owen_scrambled_radical_inverse(pc_gather_(kPrimes, first + 3u), sample,
                                       hash_uint(base_hash ^ (first + 3u)));
  }
  if (pc_any_(!halton)) {
    U a = pixel, b = sample, c = group, d = (U)(seed);
    pcg4d_lanes(&a, &b, &c, &d);
    a ^= 0x9e3779b9u; b ^= 0x85ebca6bu; c ^= 0xc2b2ae35u; d ^= 0x27d4eb2fu;
    pcg4d_lanes(&a, &b, &c, &d);
    x = select(uint_to_unit(a), x, halton);
    y = select(uint_to_unit(b), y, halton);
    z = select(uint_to_unit(c), z, halton);
    w = select(uint_to_unit(d), w, halton);
  }
  *u0 = x; *u1 = y; *u2 = z; *u3 = w;
}

#include "templates/lane_width_end.h"
