// The render loop: renders a device scene on one or several OpenCL devices at once and owns everything
// that decides when a render stops or shows its film: the schedule of work units (runtime/render_schedule.h),
// the horizons at which every pixel has the same samples, checkpoints, time and error budgets, interrupts.
// Each device is a DeviceWorker (runtime/device_worker.h) in a thread of its own. The film is a pure
// function of scene, settings and seed: the same bits for any device set of one arithmetic class, any
// split into units and any timing.
#pragma once
#include <csignal>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "runtime/device.h"
#include "runtime/device_worker.h"
#include "runtime/film.h"
#include "runtime/light_transport.h"
#include "runtime/technique.h"
#include "scene/device_scene.h"

struct RenderOptions {
  uint32_t spp = 16;
  uint32_t max_depth = 8;
  uint32_t seed = 1;
  uint32_t rr_depth = 3;       // Russian roulette only on paths longer than this many scattering events
  // Independent samples here, so that a film's per-pixel variance is an unbiased estimate of its error
  // (the statistical tests rely on it); a scene file's default is sobol (scene/scene_description.h).
  uint32_t sampler = PC_SAMPLER_INDEPENDENT;
  std::string integrator = "path";  // a technique's name (runtime/technique.h)
  uint32_t aovs = 0;               // AOVs to render beside the beauty: bits 1 << PC_AOV_* (runtime/film_layout.h)
  bool all_features = false;   // build the unspecialised kernel
  const Film* resume = nullptr; // continue from this film (its layers and spp), e.g. a checkpoint

  // When to stop before spp, and when to show the whole film at one spp.
  double time_budget = 0;       // > 0: stop at the first horizon after this many seconds of rendering
  double target_error = 0;      // > 0: stop at the first power of two spp (at least 8) whose estimated relMSE is below
  bool power_of_two_horizons = false;  // also a horizon at every power of two spp (convergence rows)
  std::string checkpoint;       // non-empty: keep the render state in this file
  double checkpoint_every = 60; // seconds between checkpoints (0: at every pass)
  uint64_t checkpoint_key = 0;  // render_key() of the scene and settings (runtime/checkpoint.h)
  const volatile std::sig_atomic_t* interrupt = nullptr;  // non-zero: stop at the next horizon

  // Work units (runtime/render_schedule.h); any choice gives the same pixels.
  uint32_t pass_spp = 0;        // samples per unit; 0 adapts units to the devices' rates
  uint32_t tile_pixels = 0;     // pixels per tile; 0: about 256 tiles
  uint32_t max_unit_pixels = 0; // 0: as the devices' rates allow
  size_t work_group = 0;        // 0: 64 (or the kernel's limit); 8 for the lane kernels; less for small CPU launches
  // Paths per work item of techniques over lanes (path, kernels/lanes.cl): 1, 8 or 16, the same pixels; 0:
  // each device's own (path_lanes, runtime/device.h), 1 for the other techniques.
  uint32_t lanes = 0;
  // Photon merging (vcm, bpm, sppm; kernels/vcm.cl): the first iteration's radius in scene units (0: a pixel's
  // footprint where the camera looks, default_merging_radius; half of it for vcm), its reduction exponent, and
  // whether vcm merges (false: bdpt's estimator, the same bits), and merging's factor in vcm's MIS weights
  // (0: the default; kernels/vcm.cl's iteration_factors).
  double radius = 0;
  double alpha = 0.75;
  bool merge = true;
  double merge_mis = 0;
  // The gathering integrators (instant_radiosity, radiosity; kernels/gather.cl): light paths per iteration
  // (0: the technique's default), instant radiosity's clamp of the geometry term (0: none) and whether
  // radiosity's camera paths gather one bounce (false: each triangle's radiosity shown).
  uint32_t light_paths = 0;
  double clamp = 0;
  bool final_gather = true;
  // Metropolis (mlt; kernels/mlt.cl): bootstrap states per depth, the probability of a large step and the
  // largest move of a small one.
  uint32_t bootstrap = 32768;
  double large_step = 0.3;
  double mutation_size = 1.0 / 32;  // docs/benchmarks-notes.md: against 1/64 and 1/16

  // Several devices.
  bool allow_mixed_devices = false;  // also use devices whose probe differs from the first device's
  // Tests only.
  bool debug_inject_hazards = false;   // make some samples NaN, infinite or negative
  bool debug_bias_diffuse = false;     // diffuse reflectance 1 % too high (the bench gate's test)
  bool debug_splat_pairs = false;      // light, bdpt: 32-bit word pairs instead of 64-bit atomics (same bits)
  int debug_bdpt_strategy_s = -1, debug_bdpt_strategy_t = -1;  // >= 0: bdpt's strategy (s, t) alone, unweighted
  // Non-zero: -DPC_BUILD_NONCE=N, a kernel no driver or cache has seen, so its first build is a cold
  // one (`pathcl bench`); the code is the same.
  uint64_t build_nonce = 0;
  std::vector<DeviceFault> faults;     // per device index (in the order given), if present
};

// What each device did.
struct DeviceReport {
  std::string name, platform;
  uint32_t rank = 0;              // the MPI rank whose device it is (runtime/ranks.h); 0 in one process
  std::string host;               // that rank's host (empty in one process)
  uint32_t arithmetic_class = 0;  // 0: the first device's; devices of other classes are left out unless mixed
  bool used = true;               // rendered units (false: left out, or failed before its first unit)
  std::string note;               // why it left or was left out
  bool sub_device = false;
  uint32_t compute_units = 0;
  uint64_t units = 0, samples = 0, duplicates_run = 0, duplicates_won = 0, failures = 0;
  double kernel_seconds = 0, transfer_seconds = 0, busy_seconds = 0, idle_seconds = 0;
  uint64_t transfer_bytes = 0;        // to and from its rank (0 for this process's devices)
  double kernel_build_ms = 0;
  bool kernel_from_cache = false;
  std::string kernel_options;
  uint64_t kernel_private_bytes = 0;  // the render kernel's private memory per work item, as the driver reports it
  uint32_t lanes = 1;                 // paths per work item
  uint32_t unit_items = 0;            // the largest unit its buffers take (pixels or paths)
  std::map<std::string, uint64_t> buffers;  // the technique's device buffers (light vertices, a grid): bytes
  double probe_seconds = 0;
};

struct RenderResult {
  Film film;
  uint64_t rays = 0, nan_samples = 0, inf_samples = 0, negative_samples = 0;
  uint64_t splat_overflows = 0;  // light: fixed-point overflows (a hazard: above zero is a bug)
  uint64_t light_vertices = 0;   // bdpt, vcm, bpm, sppm: light vertices kept on the devices, over the render
  LightTransportHeader light{};  // techniques with emission: the bounds and fixed-point scales of the film
  std::vector<PhaseTime> phases;  // device time of each named launch of the units, all devices (ms)
  double kernel_build_ms = 0;  // the slowest device's build (they build at once)
  bool kernel_from_cache = false;  // every device loaded its kernel from the cache
  std::string kernel_options;      // the first device's
  double setup_seconds = 0;        // builds, uploads and probes, before the first unit
  double render_seconds = 0;       // from the first unit to the end
  double kernel_ms = 0;            // device time of the units, all devices
  uint32_t launches = 0;           // units run (copies included)
  uint32_t horizons = 0;           // times the whole film was at one spp
  std::string stop_reason = "spp"; // spp, time, target_error or interrupted
  std::string determinism = "bitwise";  // or "mixed" (--allow-mixed-devices with several classes)
  uint32_t checkpoint_spp = 0;     // samples in the checkpoint written last (0: none)
  uint64_t duplicate_checks = 0;   // copies compared bit for bit with their twins (all equal, or it throws)
  std::vector<DeviceReport> devices;
  std::vector<std::string> warnings;
};

// Called after every committed unit (progress bars), and at every power-of-two horizon with the film
// there when RenderOptions::power_of_two_horizons (convergence rows). Neither decides anything.
struct RenderCallbacks {
  std::function<void(uint64_t samples_done, uint64_t samples_total, double seconds)> progress;
  std::function<void(const Film& film, double seconds, double kernel_build_ms)> horizon;
};

RenderResult render(const std::vector<DeviceInfo>& devices, const DeviceScene& scene, const RenderOptions& options,
                    const RenderCallbacks& callbacks = {});

// A unit worker of a render, as its thread makes it, and what the reports say of it: this process's OpenCL
// devices (device_workers) or another rank's (runtime/ranks.h).
struct WorkerSource {
  DeviceInfo info;  // another rank's device: its names, type and compute units only
  std::function<std::unique_ptr<UnitWorker>()> make;
  uint32_t rank = 0;
  std::string host;
  // Units of at least this many seconds (0: the device's usual target), counted in samples per pixel so that
  // the whole film fills them (RenderSchedule's few_units): another rank's device, whose units cross a network.
  double unit_seconds = 0;
};
// The devices as workers; with a GPU in the set, CPU devices leave one core to the host threads that feed it.
std::vector<WorkerSource> device_workers(const std::vector<DeviceInfo>& devices);
RenderResult render(const std::vector<WorkerSource>& workers, const DeviceScene& scene, const RenderOptions& options,
                    const RenderCallbacks& callbacks = {});
// One device whose context the caller keeps (tests).
RenderResult render(ClContext& cl, const DeviceScene& scene, const RenderOptions& options,
                    const RenderCallbacks& callbacks = {});
