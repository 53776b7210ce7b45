/* Counter-based random numbers: every value is a pure function of (pixel, sample index, dimension,
 * seed), so an image does not depend on work-group size, pass split or scheduling. */
#ifndef PATHCL_RNG_CL
#define PATHCL_RNG_CL

/* pcg4d (Jarzynski and Olano, "Hash Functions for GPU Rendering", JCGT 2020). */
inline uint4 pcg4d(uint4 v) {
  v = v * 1664525u + 1013904223u;
  v.x += v.y * v.w;
  v.y += v.z * v.x;
  v.z += v.x * v.y;
  v.w += v.y * v.z;
  v ^= v >> 16u;
  v.x += v.y * v.w;
  v.y += v.z * v.x;
  v.z += v.x * v.y;
  v.w += v.y * v.z;
  return v;
}

typedef struct {
  uint pixel;
  uint sample;
  uint seed;
} SampleKey;

/* Four uniform numbers in [0, 1) for dimension group `dim` (dimensions 4 dim .. 4 dim + 3). */
inline float4 sample4(SampleKey key, uint dim) {
  uint4 h = pcg4d((uint4)(key.pixel, key.sample, dim, key.seed));
  /* A second round decorrelates neighbouring counters further. */
  h = pcg4d(h ^ (uint4)(0x9e3779b9u, 0x85ebca6bu, 0xc2b2ae35u, 0x27d4eb2fu));
  return convert_float4(h >> 8u) * 0x1.0p-24f;
}

#endif
