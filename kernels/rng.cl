/* Counter-based hashing: every random value is a pure function of (pixel, sample index, dimension,
 * seed), so an image does not depend on work-group size, pass split or scheduling (see sampler.cl). */
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

#endif
