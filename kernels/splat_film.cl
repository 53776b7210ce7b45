/* The splat film (shared/light_types.h): splats from any work item to any pixel, added as unsigned 64-bit
 * fixed-point integers with atomics, so the sums are the same bits in any order of addition. With
 * cl_khr_int64_base_atomics (PC_SPLAT_ATOMIC64, set by the host where the device has it) one atom_add;
 * otherwise two 32-bit atomic_adds, the low word's carry added to the high word: the same total, since
 * addition modulo 2^64 is associative and the carries are counted exactly. No float atomics anywhere. */
#ifndef PATHCL_SPLAT_FILM_CL
#define PATHCL_SPLAT_FILM_CL

#ifdef PC_SPLAT_ATOMIC64
#pragma OPENCL EXTENSION cl_khr_int64_base_atomics : enable
#endif

/* Values at or above this many fixed-point units are too large for one splat: counted, dropped. The sums
 * are checked against 2^63 on the host, where they are final. */
#define PC_SPLAT_LIMIT 0x1.0p62f

/* Adds q to the 64-bit word pair (low word first). */
static inline void splat_add_u64(volatile __global uint* word, ulong q) {
#ifdef PC_SPLAT_ATOMIC64
  atom_add((volatile __global ulong*)word, q);
#else
  uint lo = (uint)q, hi = (uint)(q >> 32);
  uint old = atomic_add(word, lo);
  if (old + lo < old) ++hi; /* the low word wrapped around: carry one into the high word */
  if (hi) atomic_add(word + 1, hi);
#endif
}

/* The 64-bit sum of a word pair (low word first), once no more is added to it. */
static inline ulong splat_word_pair(__global const uint* word) { return (ulong)word[0] | (ulong)word[1] << 32; }

/* v (>= 0, finite) in fixed point with `scale` units per unit: false (nothing added) when too large. */
static inline bool splat_add(volatile __global uint* word, float v, float scale) {
  float q = v * scale;
  if (!(q < PC_SPLAT_LIMIT)) return false;
  ulong n = convert_ulong_rte(q);
  if (n) splat_add_u64(word, n);
  return true;
}

/* Adds colour c to pixel `pixel` of parity `parity` (the sample's parity), and its square to the squares;
 * returns the number of overflows (0 to 2). */
static inline uint splat_pixel(__global uint* film, __constant const LightTransportHeader* lt, uint pixel, uint parity, float3 c) {
  volatile __global uint* p = (volatile __global uint*)film + 2u * (PC_SPLAT_WORDS * pixel);
  uint overflows = 0u;
  float v[3] = {c.x, c.y, c.z};
  for (uint k = 0; k < 3u; ++k) {
    if (!(v[k] > 0.0f)) continue;
    if (!splat_add(p + 2u * (3u * parity + k), v[k], lt->splat_scale)) ++overflows;
    else if (!splat_add(p + 2u * (6u + k), v[k] * v[k], lt->square_scale)) ++overflows;
  }
  return overflows;
}

/* BDPT: adds a camera subpath's colour c to its own pixel, as splat_pixel does and to the camera sums. */
static inline uint splat_camera(__global uint* film, __constant const LightTransportHeader* lt, uint pixel, uint parity, float3 c) {
  volatile __global uint* p = (volatile __global uint*)film + 2u * (PC_SPLAT_WORDS * pixel);
  uint overflows = splat_pixel(film, lt, pixel, parity, c);
  float v[3] = {c.x, c.y, c.z};
  for (uint k = 0; k < 3u; ++k)
    if (v[k] > 0.0f && !splat_add(p + 2u * (9u + k), v[k], lt->splat_scale)) ++overflows;
  return overflows;
}

#endif
