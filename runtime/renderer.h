// Progressive rendering of a device scene: uploads it, builds the specialised megakernel, launches
// passes of samples and reads the film back.
#pragma once
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "runtime/device.h"
#include "scene/device_scene.h"

struct RenderOptions {
  uint32_t spp = 16;
  uint32_t max_depth = 8;
  uint32_t seed = 1;
  uint32_t rr_depth = 3;       // Russian roulette only on paths longer than this many scattering events
  uint32_t pass_spp = 0;       // samples per pixel per kernel launch; 0 picks about 2^20 samples a pass
  size_t work_group = 0;       // 0 lets the driver choose
  bool all_features = false;   // build the unspecialised kernel
};

struct RenderResult {
  uint32_t width = 0, height = 0, spp = 0;
  std::vector<float> rgb;  // width * height * 3, the mean of the samples, row 0 at the top
  uint64_t rays = 0, nan_samples = 0, inf_samples = 0, negative_samples = 0;
  double kernel_build_ms = 0;
  bool kernel_from_cache = false;
  std::string kernel_options;
  double render_seconds = 0;  // wall time of the passes, upload and read-back included
  double kernel_ms = 0;       // device time of the render passes
  uint32_t passes = 0;
};

// Called after each pass with the samples per pixel done so far.
using ProgressFn = std::function<void(uint32_t spp_done, uint32_t spp_total, double seconds)>;

RenderResult render(ClContext& cl, const DeviceScene& scene, const RenderOptions& options,
                    const ProgressFn& progress = {});
