/* Counter-based hashing: every random value is a pure function of (pixel, sample index, dimension,
 * seed), so an image does not depend on work-group size, pass split or scheduling (see sampler.cl). */
#ifndef PATHCL_RNG_CL
#define PATHCL_RNG_CL

typedef struct {
  uint pixel;
  uint sample;
  uint seed;
#ifdef PC_MLT
  struct MltSampler* mlt; /* Metropolis (mlt.cl): the state the sampler reads (sampler.cl) */
#endif
} SampleKey;

#endif
