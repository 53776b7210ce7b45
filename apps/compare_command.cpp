#include "apps/compare_command.h"

#include <cmath>
#include <cstdio>
#include <iostream>
#include <optional>
#include <string>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "runtime/errors.h"
#include "runtime/image_compare.h"
#include "runtime/image_io.h"

namespace {

struct CompareArgs {
  std::string reference, test, mask;
  bool json = false;
  double z_threshold = 3.29;  // two-sided p = 0.001 for a normal distribution
  CLI::App* command = nullptr;
};

CompareArgs& args() {
  static CompareArgs a;
  return a;
}

nlohmann::json to_json(const ImageErrors& e) {
  auto rgb = [](const double (&v)[3]) { return nlohmann::json::array({v[0], v[1], v[2]}); };
  return {{"pixels", e.pixels},
          {"rmse", e.rmse},
          {"relmse", e.rel_mse},
          {"mae", e.mae},
          {"bias", rgb(e.bias)},
          {"mean_reference", rgb(e.mean_reference)},
          {"mean_test", rgb(e.mean_test)},
          {"z_test", e.has_z_test},
          {"z_fail_fraction", e.has_z_test ? nlohmann::json(e.z_fail_fraction) : nlohmann::json(nullptr)},
          {"z_threshold", e.z_threshold}};
}

void print_text(const ImageErrors& e) {
  std::printf("pixels %zu\nrmse %.9g\nrelmse %.9g\nmae %.9g\n", e.pixels, e.rmse, e.rel_mse, e.mae);
  std::printf("bias %.9g %.9g %.9g\n", e.bias[0], e.bias[1], e.bias[2]);
  std::printf("mean_reference %.9g %.9g %.9g\n", e.mean_reference[0], e.mean_reference[1], e.mean_reference[2]);
  std::printf("mean_test %.9g %.9g %.9g\n", e.mean_test[0], e.mean_test[1], e.mean_test[2]);
  if (e.has_z_test)
    std::printf("z_fail_fraction %.9g (|z| > %g)\n", e.z_fail_fraction, e.z_threshold);
  else
    std::printf("z_test none (the test image has no variance channel)\n");
}

}  // namespace

void add_compare_command(CLI::App& app) {
  CompareArgs& a = args();
  a.command = app.add_subcommand("compare", "error metrics of an EXR image against a reference EXR");
  a.command->add_option("reference", a.reference, "reference EXR")->required();
  a.command->add_option("test", a.test, "EXR under test (variance.R/G/B channels enable the z-test)")->required();
  a.command->add_option("--mask", a.mask, "EXR whose R channel > 0 selects the pixels to compare");
  a.command->add_flag("--json", a.json, "print JSON instead of text");
  a.command->add_option("--z-threshold", a.z_threshold, "per-pixel |z| above which a pixel fails (default 3.29)");
}

bool compare_command_parsed() { return args().command && args().command->parsed(); }

int run_compare_command() {
  const CompareArgs& a = args();
  // CLI::PositiveNumber lets NaN and infinity through.
  if (!(std::isfinite(a.z_threshold) && a.z_threshold > 0))
    throw UsageError("--z-threshold: expected a finite number > 0");
  Image reference = read_exr(a.reference), test = read_exr(a.test);
  std::optional<Image> mask;
  if (!a.mask.empty()) mask = read_exr(a.mask);
  ImageErrors e;
  try {
    e = compare_images(reference, test, mask ? &*mask : nullptr, a.z_threshold);
  } catch (const UsageError& error) {
    // compare_images does not know the file names; name them here.
    std::string files = a.reference + " vs " + a.test + (mask ? " (mask " + a.mask + ")" : "");
    throw UsageError(files + ": " + error.what());
  }
  if (a.json)
    std::cout << to_json(e).dump(2) << "\n";
  else
    print_text(e);
  return 0;
}
