/* Statistics counters of the kernels, added with integer atomics. */
#ifndef PATHCL_COUNTERS_CL
#define PATHCL_COUNTERS_CL

/* Adds n to a 64-bit counter held as two words (lo, hi): the word whose addition wrapped around carries
 * into the other. Integer atomics add in any order to the same total, so the statistics are exact. */
static inline void add_counter64(volatile __global uint* lo_hi, uint n) {
  uint old = atomic_add(lo_hi, n);
  if (old + n < old) atomic_inc(lo_hi + 1);
}

#endif
