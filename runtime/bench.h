// `pathcl bench`: the OpenCL device benchmark. A fixed suite of scenes, each stressing one part of a
// device, measured for speed against error; a device's figures count only when its images pass the
// correctness gate (z-tests against references shipped in bench/references/, and analytic scenes with
// exact answers). Suite settings never change without a new kBenchSuiteVersion.
#pragma once
#include <cstdint>
#include <csignal>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "runtime/device.h"

constexpr int kBenchSuiteVersion = 1;
constexpr double kBenchTargetRelMse = 1e-2;
constexpr uint32_t kBenchReferenceSize = 64;  // the references' width and height

struct BenchSuiteSettings {
  std::string name;                 // quick or standard
  uint32_t throughput_size = 0;     // samples/s and rays/s on a film this wide and high
  uint32_t throughput_spp = 0;
  uint32_t ray_size = 0;            // camera rays: one per pixel of a film this wide and high
  int ray_repeats = 0;              // timed traversals, the median counts
  int timing_repeats = 0;           // renders for samples/s and for the time to relMSE 1e-2, the median counts
  double convergence_seconds = 0;   // at most this long towards relMSE 1e-2 (then extrapolated)
  double timed_seconds = 0;         // each render timed for the time to relMSE 1e-2 lasts at least this long
};
// "quick", "standard", or "test" (CTest: small films, no cold builds). UsageError for others.
BenchSuiteSettings bench_suite(const std::string& name);

// The suite's scenes, in order: cornell-box, glass-metal, terrain, textured.
std::vector<std::string> bench_scene_names();
// Writes every scene file of the suite (and the terrain mesh and texture it generates) into dir;
// returns the scene files by name order. The references are renders of exactly these files.
std::vector<std::string> write_bench_scenes(const std::string& dir);

struct GateResult {
  double pixel_fail_fraction = 0;  // pixels with |z| > 3.29 in some channel (reported, see bench.cpp)
  double block_fail_fraction = 0;  // 4 x 4 pixel blocks with |z| > 4 in some channel
  double mean_z[3] = {};           // per channel: (mean test - mean reference) / its standard error
  bool passed = false;
  std::string failure;             // what failed, "" when passed
};

struct BenchSceneResult {
  std::string name;
  uint64_t triangles = 0;
  std::optional<double> kernel_build_cold_ms;  // absent in the test suite
  double kernel_build_cached_ms = 0, upload_ms = 0;
  double camera_rays_per_second = 0, bounce_rays_per_second = 0;
  double samples_per_second = 0;           // on the throughput film
  double seconds_to_target = 0;            // to relMSE 1e-2 against the reference (see bench.cpp)
  bool target_reached = false;             // false: extrapolated from the error at the time limit
  uint32_t spp_at_end = 0;
  double rel_mse_at_end = 0;
  GateResult gate;
};

struct AnalyticResult {
  std::string name;
  double expected = 0, mean = 0, std_error = 0;
  bool passed = false;
};

struct BenchDeviceResult {
  std::vector<std::string> devices;       // one name, or several for the devices together
  std::string platform, driver;
  std::string class_hash;                 // hash of the pixels of a fixed small render
  bool same_bits_as_pocl = false;         // class_hash == kBenchPoclHash
  std::vector<BenchSceneResult> scenes;
  std::vector<AnalyticResult> analytic;
  bool passed = false;
  std::vector<std::string> failures;
  double score_samples = 0;               // geometric mean of Msamples/s over the scenes
  double score_convergence = 0;           // geometric mean of 1 / seconds to relMSE 1e-2
  bool interrupted = false;
};

// The hash of the fixed render that PoCL gives (bench.cpp); a device that gives another computes other bits.
extern const char* const kBenchPoclHash;

struct BenchOptions {
  BenchSuiteSettings suite;
  std::string work_dir;                    // scene files and kernel caches for cold builds
  std::vector<std::string> only;           // a subset of the scenes (then the score is partial)
  bool debug_bias_diffuse = false;         // test: a 1 % biased diffuse BSDF must fail the gate
  const volatile std::sig_atomic_t* interrupt = nullptr;
  std::function<void(const std::string& what)> progress;  // one line per step
};

// One device, or several together (then no rays/s and no cold builds: those are per device).
BenchDeviceResult run_bench(const std::vector<DeviceInfo>& devices, const BenchOptions& options);
// The hash of the pixels of a fixed render (cornell-box at 32 x 32, 4 spp, sobol) on these devices;
// its scene file is written into work_dir.
std::string bench_class_hash(const std::vector<DeviceInfo>& devices, const std::string& work_dir);
