/* The light-tracing integrator (`light`): light path `index` of sample s is keyed by (index, s): sample s
 * holds width x height light paths, so a light render of N spp traces as many paths as a path render of N
 * spp. The light paths themselves, their camera connections and splats are light_path.cl's (BDPT traces the
 * same ones). A work item traces W = PC_LANES paths at once (kernels/lanes.cl: 1 on GPUs, 8 or 16 on CPU
 * devices), a lane each, bounce by bounce: every path is the one-lane path, bit for bit. */
#include "light_path.cl"

/* One work unit: light paths [path_begin, path_begin + path_count) of samples [sample_begin, sample_begin +
 * sample_count), splatted into film (PC_SPLAT_WORDS 64-bit sums per pixel, cleared by the host per unit).
 * Work item i traces paths i G .. i G + G - 1 (G = PC_ITEM_PIXELS: W x PC_LANE_PIXELS, 1 for one lane), W at
 * a time. Which work item or lane runs which path, and in which order splats arrive, changes no bit of the film. */
PC_KERNEL_BODY void light_pass_item(const SceneData* scene, __constant const LightTransportHeader* lt,
                                    __global const float* emission_cdf, __global uint* film, __global SplatStats* stats,
                                    uint path_begin, uint path_count, uint sample_begin, uint sample_count, uint item) {
  SceneData sc = *scene;
  __constant const SceneHeader* h = sc.h;
  uint first = item * PC_ITEM_PIXELS;
  if (first >= path_count) return;
  LaneU lane = lane_indices();
  SampleKey key = light_path_key(h, path_begin + first, sample_begin);
  SplatCounts n = {0u, 0u, 0u, 0u, 0u, 0u};
  for (uint s = sample_begin; s < sample_begin + sample_count; ++s) {
    key.sample = s;
    for (uint b = first; b < min(first + PC_ITEM_PIXELS, path_count); b += PC_LANES) {
      LaneU index = (LaneU)(b) + lane;
      key.pixel = path_begin + b;
      trace_light_paths_lanes(&sc, lt, emission_cdf, film, key, (LaneU)(path_begin) + index, index < path_count, &n);
    }
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
