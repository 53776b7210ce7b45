#include "apps/bench_command.h"

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <sstream>

#include <unistd.h>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "runtime/atomic_file.h"
#include "runtime/bench.h"
#include "runtime/errors.h"
#include "runtime/interrupt.h"
#include "runtime/output_files.h"

namespace {

struct BenchArgs {
  CLI::App* command = nullptr;
  std::string device, suite = "quick", json, only, write_scenes;
  bool check = false, inject_bias = false;
};

BenchArgs& args() {
  static BenchArgs a;
  return a;
}

std::string join(const std::vector<std::string>& v, const char* sep) {
  std::string s;
  for (const std::string& x : v) s += (s.empty() ? "" : sep) + x;
  return s;
}

std::vector<std::string> split(const std::string& list) {
  std::vector<std::string> items;
  std::stringstream in(list);
  for (std::string item; std::getline(in, item, ',');) items.push_back(item);
  return items;
}

void print_result(const BenchDeviceResult& r) {
  std::printf("\n%s (%s, driver %s): %s\n", join(r.devices, " + ").c_str(), r.platform.c_str(), r.driver.c_str(),
              r.interrupted ? "INTERRUPTED" : r.passed ? "PASSED" : "FAILED");
  std::printf("  arithmetic class %s (PoCL gives %s: %s)\n", r.class_hash.c_str(), kBenchPoclHash,
              r.same_bits_as_pocl ? "the same bits" : "other bits");
  std::printf("  %-12s %9s %10s %8s %8s %9s %9s %10s %10s  %s\n", "scene", "triangles", "build cold", "cached", "upload",
              "cam Mr/s", "bnc Mr/s", "Msamples/s", "s to 1e-2", "gate");
  for (const BenchSceneResult& s : r.scenes) {
    char cold[32] = "-";
    if (s.kernel_build_cold_ms) std::snprintf(cold, sizeof cold, "%.0f ms", *s.kernel_build_cold_ms);
    std::printf("  %-12s %9llu %10s %5.0f ms %5.1f ms %9.2f %9.2f %10.3f %9.3f%s  %s\n", s.name.c_str(),
                (unsigned long long)s.triangles, cold, s.kernel_build_cached_ms, s.upload_ms,
                s.camera_rays_per_second * 1e-6, s.bounce_rays_per_second * 1e-6, s.samples_per_second * 1e-6,
                s.seconds_to_target, s.target_reached ? " " : "*",
                s.gate.passed ? "pass" : ("FAILED: " + s.gate.failure).c_str());
  }
  for (const AnalyticResult& a : r.analytic)
    std::printf("  analytic %-12s mean %.6f, exact %.6f, standard error %.2g: %s\n", a.name.c_str(), a.mean, a.expected,
                a.std_error, a.passed ? "pass" : "FAILED");
  if (std::any_of(r.scenes.begin(), r.scenes.end(), [](const BenchSceneResult& s) { return !s.target_reached; }))
    std::printf("  * extrapolated: relMSE 1e-2 was not reached within the suite's time limit\n");
  if (r.passed)
    std::printf("  score: %.3f Msamples/s, %.3f / s to relMSE 1e-2 (geometric means over %zu scenes)\n", r.score_samples,
                r.score_convergence, r.scenes.size());
  else
    for (const std::string& f : r.failures) std::printf("  no score: %s\n", f.c_str());
}

nlohmann::json to_json(const BenchDeviceResult& r) {
  nlohmann::json scenes = nlohmann::json::array(), analytic = nlohmann::json::array();
  for (const BenchSceneResult& s : r.scenes)
    scenes.push_back({{"name", s.name},
                      {"triangles", s.triangles},
                      {"kernel_build_cold_ms", s.kernel_build_cold_ms ? nlohmann::json(*s.kernel_build_cold_ms) : nullptr},
                      {"kernel_build_cached_ms", s.kernel_build_cached_ms},
                      {"upload_ms", s.upload_ms},
                      {"camera_rays_per_second", s.camera_rays_per_second},
                      {"bounce_rays_per_second", s.bounce_rays_per_second},
                      {"samples_per_second", s.samples_per_second},
                      {"seconds_to_relmse_1e-2", s.seconds_to_target},
                      {"relmse_1e-2_reached", s.target_reached},
                      {"spp_at_end", s.spp_at_end},
                      {"relmse_at_end", s.rel_mse_at_end},
                      {"gate", {{"passed", s.gate.passed},
                                {"pixel_fail_fraction", s.gate.pixel_fail_fraction},
                                {"block_fail_fraction", s.gate.block_fail_fraction},
                                {"mean_z", {s.gate.mean_z[0], s.gate.mean_z[1], s.gate.mean_z[2]}},
                                {"failure", s.gate.failure}}}});
  for (const AnalyticResult& a : r.analytic)
    analytic.push_back({{"name", a.name}, {"expected", a.expected}, {"mean", a.mean}, {"std_error", a.std_error},
                        {"passed", a.passed}});
  return {{"devices", r.devices},
          {"platform", r.platform},
          {"driver", r.driver},
          {"class_hash", r.class_hash},
          {"pocl_class_hash", kBenchPoclHash},
          {"same_bits_as_pocl", r.same_bits_as_pocl},
          {"verdict", r.interrupted ? "INTERRUPTED" : r.passed ? "PASSED" : "FAILED"},
          {"failures", r.failures},
          {"scenes", scenes},
          {"analytic", analytic},
          {"score", r.passed ? nlohmann::json({{"msamples_per_second", r.score_samples},
                                              {"per_second_to_relmse_1e-2", r.score_convergence}})
                             : nlohmann::json(nullptr)}};
}

}  // namespace

void add_bench_command(CLI::App& app) {
  BenchArgs& a = args();
  a.command = app.add_subcommand("bench", "benchmark OpenCL devices: speed against error, scored only when correct");
  a.command->add_option("--device", a.device,
                        "device index or name substring, cpu, gpu, a comma-separated list of them, or all (each "
                        "device alone, then all of them together)");
  a.command->add_option("--suite", a.suite, "quick (under a minute on 2 CPU cores), standard (a few minutes)");
  a.command->add_option("--json", a.json, "write every figure as JSON");
  a.command->add_flag("--check", a.check, "exit 1 when a device fails the correctness gate");
  a.command->add_option("--only", a.only, "a comma-separated subset of the scenes (the score is then partial)");
  a.command->add_option("--write-scenes", a.write_scenes,
                        "write the suite's scene files into this directory and stop (what the references render)");
  // Test only: build the kernels with a 1 % biased diffuse BSDF, which the gate must report.
  a.command->add_flag("--debug-bias-diffuse", a.inject_bias)->group("");
}

bool bench_command_parsed() { return args().command && args().command->parsed(); }

int run_bench_command(const std::string& pathcl_version) {
  const BenchArgs& a = args();
  if (!a.write_scenes.empty()) {
    for (const std::string& file : write_bench_scenes(a.write_scenes)) std::printf("%s\n", file.c_str());
    return 0;
  }
  BenchOptions options;
  options.suite = bench_suite(a.suite);
  options.only = split(a.only);
  options.debug_bias_diffuse = a.inject_bias;
  check_output_files({{"--json", a.json}});
  std::vector<DeviceInfo> devices = select_devices(a.device.empty() ? "" : a.device);

  char pattern[] = "/tmp/pathcl-bench-XXXXXX";
  if (!mkdtemp(pattern)) throw RuntimeFailure("cannot make a temporary directory for the benchmark");
  options.work_dir = pattern;
  install_stop_handlers("the benchmark is not finished" + (a.json.empty() ? std::string() : "; " + a.json + " is not written"));
  options.interrupt = stop_signal();
  bool tty = isatty(STDERR_FILENO);
  std::string current;
  options.progress = [&](const std::string& what) {
    if (tty) std::fprintf(stderr, "\r\033[K%s: %s", current.c_str(), what.c_str());
  };

  std::vector<BenchDeviceResult> results;
  std::vector<std::vector<DeviceInfo>> runs;
  for (const DeviceInfo& d : devices) runs.push_back({d});
  if (devices.size() > 1) runs.push_back(devices);
  std::printf("pathcl bench: suite %s (version %d), pathcl %s\n", options.suite.name.c_str(), kBenchSuiteVersion,
              pathcl_version.c_str());
  std::fflush(stdout);  // the signal handlers are in place from here on
  for (const auto& run : runs) {
    if (*stop_signal()) break;
    current = run.size() == 1 ? run.front().name : "together";
    results.push_back(run_bench(run, options));
    if (tty) std::fprintf(stderr, "\r\033[K");
    print_result(results.back());
    std::fflush(stdout);
  }
  std::error_code ec;
  std::filesystem::remove_all(options.work_dir, ec);

  if (!a.json.empty()) {
    nlohmann::json list = nlohmann::json::array();
    for (const BenchDeviceResult& r : results) list.push_back(to_json(r));
    nlohmann::json j = {{"pathcl", pathcl_version},
                        {"suite", {{"name", options.suite.name}, {"version", kBenchSuiteVersion}}},
                        {"scenes_run", options.only.empty() ? bench_scene_names() : options.only},
                        {"results", list}};
    write_text_file(a.json, j.dump(2) + "\n");  // also when interrupted: what was measured, marked so
  }
  if (int signal = *stop_signal()) {
    std::fprintf(stderr, "interrupted: the figures above are what was measured; no score\n");
    return 128 + signal;
  }
  bool failed = std::any_of(results.begin(), results.end(), [](const BenchDeviceResult& r) { return !r.passed; });
  return a.check && failed ? 1 : 0;
}
