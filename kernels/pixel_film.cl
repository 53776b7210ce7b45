/* The pixel film's accumulators (integrator.cl, gather.cl): per pixel the sums of the even- and of the
 * odd-numbered samples (w counts them) and the sum of squares, three float4, each pixel's samples added in
 * sample order. */
#ifndef PATHCL_PIXEL_FILM_CL
#define PATHCL_PIXEL_FILM_CL

/* Adds sample s's radiance to a pixel's accumulators (even and odd half sums, squares). A sample that is
 * not a finite non-negative radiance is counted and dropped: it is a bug to find. */
static inline void accumulate_sample(float3 L, uint s, float4* half_sum, float4* squares, uint* nan_samples,
                                     uint* inf_samples, uint* negative_samples) {
#ifdef PC_DEBUG_INJECT_HAZARDS
  /* Test builds only (RenderOptions::debug_inject_hazards): proves that the hazard counters count. */
  if (s % 7u == 3u) L.x = NAN;
  if (s % 11u == 5u) L.y = INFINITY;
  if (s % 13u == 6u) L.z = -1.0f;
#endif
  if (isnan(L.x) || isnan(L.y) || isnan(L.z)) {
    ++*nan_samples;
    L = (float3)(0.0f);
  } else if (isinf(L.x) || isinf(L.y) || isinf(L.z)) {
    ++*inf_samples;
    L = (float3)(0.0f);
  } else if (L.x < 0.0f || L.y < 0.0f || L.z < 0.0f) {
    ++*negative_samples;
    L = (float3)(0.0f);
  }
  half_sum[s & 1u] += (float4)(L, 1.0f);
  squares->xyz += L * L;
}

#endif
