// Progressive rendering of a device scene: uploads it, builds the specialised megakernel, launches
// passes of samples and reads the film back.
#pragma once
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "runtime/device.h"
#include "scene/device_scene.h"

struct Film;

struct RenderOptions {
  uint32_t spp = 16;
  uint32_t max_depth = 8;
  uint32_t seed = 1;
  uint32_t rr_depth = 3;       // Russian roulette only on paths longer than this many scattering events
  // Independent samples here, so that a film's per-pixel variance is an unbiased estimate of its error
  // (the statistical tests rely on it); a scene file's default is sobol (scene/scene_description.h).
  uint32_t sampler = PC_SAMPLER_INDEPENDENT;
  uint32_t pass_spp = 0;       // samples per pixel per kernel launch; 0 adapts launches to 50-100 ms
  double max_pass_seconds = 0;  // > 0: shrink passes that take longer (keeps a time budget's overrun small)
  size_t max_pixels_per_launch = 0;  // 0: the whole film (adaptive sizing may still split it)
  bool power_of_two_passes = false;  // also end a pass at every power of two spp (for convergence rows)
  size_t work_group = 0;       // 0 lets the driver choose
  bool all_features = false;   // build the unspecialised kernel
  const Film* resume = nullptr; // continue from this film (its accumulators and spp), e.g. a checkpoint
  bool debug_inject_hazards = false;  // tests only: make some samples NaN, infinite or negative
};

// The film as read back: per pixel RGB, row 0 at the top.
struct Film {
  uint32_t width = 0, height = 0, spp = 0;
  std::vector<float> mean;      // the mean of all samples
  std::vector<float> variance;  // the estimated variance of that mean (sample variance / spp)
  std::vector<float> even_mean, odd_mean;  // means of the even- and odd-numbered samples
  // The device's accumulators, 3 per pixel: even-sample sum (w: count), odd-sample sum, sum of squares.
  std::vector<pc_float4> accumulators;
};

// Derives the means and variances from accumulators (3 per pixel).
Film film_from_accumulators(uint32_t width, uint32_t height, std::vector<pc_float4> accumulators);

// The relative MSE of the film's mean, estimated from the difference of its two half images:
// mean over pixels and channels of E[(even - odd)^2] scaled to one full mean, over (mean^2 + 0.01).
double estimated_rel_mse(const Film& film);

// GPU launch sizing (RenderOptions::pass_spp = 0 on a GPU): after each pass, the samples per pass and
// pixels per launch move towards a slowest launch of 50-100 ms, long enough to amortise a launch and
// short enough that a desktop watchdog never kills one.
struct LaunchSize {
  uint32_t pass_spp = 1;
  size_t launch_pixels = 0;
};
LaunchSize adapt_launch_size(LaunchSize size, double slowest_launch_ms, size_t pixels);

struct RenderResult {
  Film film;
  uint64_t rays = 0, nan_samples = 0, inf_samples = 0, negative_samples = 0;
  double kernel_build_ms = 0;
  bool kernel_from_cache = false;
  std::string kernel_options;
  double render_seconds = 0;  // wall time of the passes, upload and read-back included
  double kernel_ms = 0;       // device time of the render passes
  uint32_t passes = 0;    // sample ranges, each over every pixel
  uint32_t launches = 0;  // kernel launches (a pass may be split into pixel ranges)
  bool stopped_early = false; // the observer ended the render before options.spp
};

struct PassInfo {
  uint32_t spp_done = 0, spp_total = 0;
  double seconds = 0;  // since the render started (after the kernel build)
  double kernel_build_ms = 0;
};

// Called after each pass. read_film() reads the film back (costly: call it only when needed).
// Returning false stops the render after this pass.
using PassObserver = std::function<bool(const PassInfo& pass, const std::function<Film()>& read_film)>;

RenderResult render(ClContext& cl, const DeviceScene& scene, const RenderOptions& options,
                    const PassObserver& observer = {});
