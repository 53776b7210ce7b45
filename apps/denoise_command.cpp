#include "apps/denoise_command.h"

#include <chrono>
#include <cstdio>
#include <string>

#include <CLI/CLI.hpp>

#include "runtime/denoise.h"
#include "runtime/errors.h"
#include "runtime/image_io.h"
#include "runtime/output_files.h"

namespace {

struct DenoiseArgs {
  std::string input, output;
  bool no_aux = false, quiet = false;
  std::string aux = "albedo,normal", quality = "high";
  CLI::App* command = nullptr;
};

DenoiseArgs& args() {
  static DenoiseArgs a;
  return a;
}

}  // namespace

void add_denoise_command(CLI::App& app) {
  DenoiseArgs& a = args();
  a.command = app.add_subcommand("denoise", "denoise an EXR image with Intel Open Image Denoise");
  a.command->add_option("input", a.input, "EXR to denoise (its layers albedo.R/G/B and normal.X/Y/Z guide the denoiser)")
      ->required();
  a.command->add_option("-o,--output", a.output, "output EXR: the denoised R, G, B, the input as the layer raw")->required();
  CLI::Option* aux = a.command->add_option("--aux", a.aux,
                                           "the layers that guide the denoiser: albedo,normal (the default), albedo or "
                                           "none; a missing one is an error");
  a.command->add_flag("--no-aux", a.no_aux, "denoise the colour alone (--aux none)")->excludes(aux);
  a.command->add_option("--quality", a.quality, "high (the default), balanced or fast");
  a.command->add_flag("-q,--quiet", a.quiet, "no summary line on stderr");
}

bool denoise_command_parsed() { return args().command && args().command->parsed(); }

int run_denoise_command() {
  const DenoiseArgs& a = args();
  if (a.quality != "high" && a.quality != "balanced" && a.quality != "fast")
    throw UsageError("--quality " + a.quality + ": expected high, balanced or fast");
  std::string aux = a.no_aux ? "none" : a.aux;
  if (aux != "albedo,normal" && aux != "normal,albedo" && aux != "albedo" && aux != "none")
    throw UsageError("--aux " + aux + ": expected albedo,normal, albedo or none (a normal guides only beside an albedo)");
  check_output_files({{"-o", a.output, true}});
  Image image = read_exr(a.input);
  DenoiseOptions options;
  options.use_albedo = aux != "none";
  options.use_normal = aux.find("normal") != std::string::npos;
  options.quality = a.quality;
  const bool denoised_before = find_layer(image, "raw") != nullptr;
  auto start = std::chrono::steady_clock::now();
  denoise_image(image, options, a.input);
  double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  write_image(a.output, image);
  if (!a.quiet)
    // scripts/bench/denoise reads this line up to "aux ...)".
    std::fprintf(stderr, "%s: denoised %ux%u in %.2f s with %s (quality %s, aux %s) on %s%s -> %s\n", a.input.c_str(),
                 image.width, image.height, seconds, image.attributes["denoiser"].c_str(), a.quality.c_str(),
                 image.attributes["denoiser_aux"].c_str(), image.attributes["denoiser_device"].c_str(),
                 denoised_before ? ", from its raw layer (it was denoised before)" : "", a.output.c_str());
  return 0;
}
