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

inline uint hash_uint(uint x) { /* lowbias32 (Wellons) */
  x ^= x >> 16;
  x *= 0x7feb352du;
  x ^= x >> 15;
  x *= 0x846ca68bu;
  x ^= x >> 16;
  return x;
}

inline uint hash4(uint a, uint b, uint c, uint d) { return pcg4d((uint4)(a, b, c, d)).x; }

inline float uint_to_unit(uint x) { return (float)(x >> 8) * 0x1.0p-24f; }

inline uint reverse_bits(uint x) {
  x = ((x >> 1) & 0x55555555u) | ((x & 0x55555555u) << 1);
  x = ((x >> 2) & 0x33333333u) | ((x & 0x33333333u) << 2);
  x = ((x >> 4) & 0x0f0f0f0fu) | ((x & 0x0f0f0f0fu) << 4);
  x = ((x >> 8) & 0x00ff00ffu) | ((x & 0x00ff00ffu) << 8);
  return (x >> 16) | (x << 16);
}

/* Laine-Karras style permutation with Burley's constants: an Owen scramble of the reversed bits. */
inline uint nested_uniform_scramble(uint x, uint seed) {
  x = reverse_bits(x);
  x += seed;
  x ^= x * 0x6c50b47cu;
  x ^= x * 0xb82f1e52u;
  x ^= x * 0xc7afe638u;
  x ^= x * 0x8d22f6e6u;
  return reverse_bits(x);
}

/* Sobol dimension dim in 1..3 of a 32-bit index, as bits. */
inline uint sobol_bits(uint index, uint dim) {
  uint x = 0u;
  for (uint n = 0u; n < 8u; ++n) x ^= kSobolNibbles[dim - 1u][n][(index >> (4u * n)) & 15u];
  return x;
}

/* A random permutation of [0, n): Kensler's hashed bijection of the next power of two, cycle-walked into
 * [0, n), then rotated. The rotation uses a second hash: Kensler's original rotation by p itself is
 * correlated with the bijection and made the marginal of small permutations non-uniform (a measurable
 * bias of Owen-scrambled Halton at low spp). */
inline uint permute_index(uint i, uint n, uint p) {
  uint w = n - 1u;
  w |= w >> 1; w |= w >> 2; w |= w >> 4; w |= w >> 8; w |= w >> 16;
  do {
    i ^= p; i *= 0xe170893du; i ^= p >> 16; i ^= (i & w) >> 4; i ^= p >> 8; i *= 0x0929eb3fu; i ^= p >> 23;
    i ^= (i & w) >> 1; i *= 1u | p >> 27; i *= 0x6935fa69u; i ^= (i & w) >> 11; i *= 0x74dcb303u;
    i ^= (i & w) >> 2; i *= 0x9e501cc3u; i ^= (i & w) >> 2; i *= 0xc860a3dfu; i &= w; i ^= i >> 5;
  } while (i >= n);
  return (i + hash_uint(p ^ 0x68bc21ebu)) % n;
}

/* One pair of stratified dimensions: the sample's stratum in an nx x ny grid, jittered. */
inline float2 stratified_pair(SampleKey key, uint spp, uint pair_id) {
  uint nx = max(1u, (uint)sqrt((float)spp)), ny = max(1u, spp / nx), n = nx * ny;
  uint h = hash4(key.pixel, pair_id, key.seed, 0x5851f42du);
  float2 jitter = (float2)(uint_to_unit(hash4(key.pixel, key.sample, pair_id, key.seed ^ 0x2545f491u)),
                           uint_to_unit(hash4(key.sample, key.pixel, pair_id, key.seed ^ 0x9e3779b9u)));
  uint stratum = permute_index(key.sample % n, n, h);
  return (float2)(((float)(stratum % nx) + jitter.x) / (float)nx, ((float)(stratum / nx) + jitter.y) / (float)ny);
}

inline float owen_scrambled_radical_inverse(uint base, uint a, uint hash) {
  float inv_base = 1.0f / (float)base, inv_base_m = 1.0f;
  uint reversed = 0u, digit_count = 0u;
  /* Digits until they no longer change a float in [0, 1). */
  while (1.0f - inv_base_m < 1.0f && inv_base_m > 0x1.0p-24f) {
    uint next = a / base, digit = a - next * base;
    /* Each node of the digit tree (the digits below it) permutes its digit with its own hash. */
    digit = permute_index(digit, base, hash_uint(hash ^ (reversed * 0x9e3779b9u + digit_count)));
    reversed = reversed * base + digit;
    inv_base_m *= inv_base;
    ++digit_count;
    a = next;
  }
  return fmin(inv_base_m * (float)reversed, 0x1.fffffep-1f);
}

/* Four uniform numbers in [0, 1) for dimensions 4 group .. 4 group + 3. */
inline float4 sample4(__constant const SceneHeader* h, SampleKey key, uint group) {
  if (h->sampler == PC_SAMPLER_STRATIFIED) {
    return (float4)(stratified_pair(key, h->spp, 2u * group), stratified_pair(key, h->spp, 2u * group + 1u));
  }
  if (h->sampler == PC_SAMPLER_SOBOL) {
    uint seed = hash4(key.pixel, group, key.seed, 0x68e31da4u);
    uint index = nested_uniform_scramble(key.sample, seed);
    float4 u;
    u.x = uint_to_unit(nested_uniform_scramble(reverse_bits(index), hash_uint(seed ^ 0x1u))); /* = sobol_bits(index, 0) */
    u.y = uint_to_unit(nested_uniform_scramble(sobol_bits(index, 1u), hash_uint(seed ^ 0x2u)));
    u.z = uint_to_unit(nested_uniform_scramble(sobol_bits(index, 2u), hash_uint(seed ^ 0x3u)));
    u.w = uint_to_unit(nested_uniform_scramble(sobol_bits(index, 3u), hash_uint(seed ^ 0x4u)));
    return u;
  }
  if (h->sampler == PC_SAMPLER_HALTON && 4u * group + 3u < PC_HALTON_DIMENSIONS) {
    uint base_hash = hash4(key.pixel, key.seed, 0xb5297a4du, 0u);
    float4 u;
    u.x = owen_scrambled_radical_inverse(kPrimes[4u * group], key.sample, hash_uint(base_hash ^ (4u * group)));
    u.y = owen_scrambled_radical_inverse(kPrimes[4u * group + 1u], key.sample, hash_uint(base_hash ^ (4u * group + 1u)));
    u.z = owen_scrambled_radical_inverse(kPrimes[4u * group + 2u], key.sample, hash_uint(base_hash ^ (4u * group + 2u)));
    u.w = owen_scrambled_radical_inverse(kPrimes[4u * group + 3u], key.sample, hash_uint(base_hash ^ (4u * group + 3u)));
    return u;
  }
  uint4 x = pcg4d((uint4)(key.pixel, key.sample, group, key.seed));
  x = pcg4d(x ^ (uint4)(0x9e3779b9u, 0x85ebca6bu, 0xc2b2ae35u, 0x27d4eb2fu));
  return convert_float4(x >> 8u) * 0x1.0p-24f;
}

#endif
