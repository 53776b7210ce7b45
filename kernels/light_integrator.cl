/* The light-tracing integrator (`light`, lane width 1: one work item traces one light path at a time,
 * scalar code like the path megakernel). Light path `index` of sample s is keyed by (index, s): sample
 * s holds width x height light paths, so a light render of N spp traces as many paths as a path render
 * of N spp. The light paths themselves, their camera connections and splats are light_path.cl's (BDPT
 * traces the same ones). */
#include "light_path.cl"

/* One work unit: light paths [path_begin, path_begin + path_count) of samples [sample_begin, sample_begin +
 * sample_count), splatted into film (PC_SPLAT_WORDS 64-bit sums per pixel, cleared by the host per unit).
 * Which work item runs which path, and in which order splats arrive, changes no bit of the film. */
PC_KERNEL_BODY void light_pass_item(const SceneData* scene, __constant const LightTransportHeader* lt,
                                    __global const float* emission_cdf, __global uint* film, __global SplatStats* stats,
                                    uint path_begin, uint path_count, uint sample_begin, uint sample_count, uint item) {
  SceneData sc = *scene;
  __constant const SceneHeader* h = sc.h;
  if (item >= path_count) return;
  SampleKey key = light_path_key(h, path_begin + item, sample_begin);
  SplatCounts n = {0u, 0u, 0u, 0u, 0u, 0u};
  for (uint s = sample_begin; s < sample_begin + sample_count; ++s) {
    key.sample = s;
    trace_light_path(&sc, lt, emission_cdf, film, key, &n);
  }
  add_splat_counts(stats, &n);
}
__kernel void light_pass(PC_SCENE_PARAMS, __constant const LightTransportHeader* lt, __global const float* emission_cdf,
                         __global uint* film, __global SplatStats* stats, uint path_begin, uint path_count,
                         uint sample_begin, uint sample_count) {
  SceneData sc = PC_SCENE_DATA;
  light_pass_item(&sc, lt, emission_cdf, film, stats, path_begin, path_count, sample_begin, sample_count,
                  get_global_id(0));
}
