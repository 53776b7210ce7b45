// Denoising with Intel Open Image Denoise 2.x (OIDN), loaded at run time with dlopen: pathcl builds and
// runs without it, and only denoising needs it. The library is searched for at
//   1. $PATHCL_OIDN_LIBRARY, a file path (when set, only there),
//   2. the build's build/oidn-venv (the PyPI package pyoidn, which scripts/setup installs), whose
//      libOpenImageDenoise.so.2* is looked up at run time,
//   3. dlopen("libOpenImageDenoise.so.2"), i.e. the system's library path.
// It runs OIDN's CPU device and its "RT" filter in HDR mode.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "runtime/image_io.h"

// The value of the attribute "determinism" of a denoised image. A render's "bitwise" promises the same
// bits on any conformant OpenCL device; OIDN does not: its CPU device picks its kernels by the CPU's
// instruction set (SSE4, AVX2, AVX-512, AMX), and they block and sum differently. The denoised beauty is
// the same bits again only from the same library build ("denoiser") on the same kind of device and CPU
// ("denoiser_device"; OIDN does not report the instruction set it picked); 1 and 2 threads gave the same
// bits (docs/denoising.md). The render's own value goes to "raw.determinism", beside the raw layer.
inline constexpr const char* kDenoisedDeterminism = "denoiser-dependent";

struct DenoiseOptions {
  // The guides denoise_image uses: the layers "albedo" (R, G, B) and "normal" (X, Y, Z). One asked for and
  // missing is a UsageError, never a quiet fall-back to fewer guides. OIDN takes a normal only beside an
  // albedo, so use_normal without use_albedo is a UsageError too.
  bool use_albedo = true, use_normal = true;
  // With both albedo and normal: denoise them first (OIDN's prefiltering) and tell the filter that they
  // are clean (cleanAux). Without it, OIDN takes them as noisy. It costs: at quality high OIDN runs its
  // large networks for the albedo, the normal and the beauty, about 7x the time of the beauty alone.
  bool clean_aux = true;
  std::string quality = "high";  // high, balanced or fast (OIDN's quality modes)
};

struct DenoiseResult {
  std::vector<float> rgb;       // width * height * 3, the denoised image
  std::string library_version;  // "2.5.1"
  // The device OIDN ran on: its type and its physical device's name, "CPU: Intel(R) Xeon(R) Processor".
  std::string device;
  bool used_albedo = false, used_normal = false;
  double seconds = 0;  // wall time of the call: OIDN device, filters and their execution
};

// Whether the library loads and its CPU device starts; if not, *why (when given) says why and how to get
// it.
bool denoiser_available(std::string* why = nullptr);

// Denoises an HDR image (width * height * 3 floats, interleaved, any row order as long as all images
// agree), with the optional albedo (values in [0, 1]) and normal (values in [-1, 1]) images of the same
// size. OIDN takes a normal only beside an albedo: a normal alone is not used (used_normal says so).
// RuntimeFailure when the library is missing (the message says how to get it) or OIDN fails;
// UsageError for an unknown quality or buffers of the wrong size.
DenoiseResult denoise(uint32_t width, uint32_t height, const std::vector<float>& rgb, const std::vector<float>* albedo,
                      const std::vector<float>* normal, const DenoiseOptions& options);

// Denoises an image in place, as `pathcl denoise` and `pathcl render --denoise` do; rgb becomes the
// denoised beauty, guided by the layers "albedo" (R, G, B) and "normal" (X, Y, Z) as options say.
// The input beauty is the image's R, G, B, which move into a new layer "raw" (R, G, B); but an image with
// a layer "raw" was denoised before, and then that layer, the render, is denoised again (with these
// options) and kept as it is: a denoised image is never denoised twice, and its raw layer never replaced.
// What describes the raw beauty goes beside it, so that no tool takes it for the denoised one's: the
// variance (variance.R/G/B) becomes the layer "raw.variance" (R, G, B), leaving the image without a
// top-level variance, and the attribute "determinism" becomes "raw.determinism" (both kept from an image
// denoised before), "determinism" being set to kDenoisedDeterminism. The attributes "denoiser" ("Intel
// Open Image Denoise 2.5.1"), "denoiser_device" (DenoiseResult::device), "denoiser_quality" and
// "denoiser_aux" ("albedo,normal", "albedo" or "none") are set. Other layers and attributes are kept.
// UsageError naming `source` (the file) for a layer "raw" that is not float R, G, B, or a guide that
// options ask for and the image lacks (the message names the layer or channel, and the options that ask
// for fewer guides); the image is then unchanged, as it is when OIDN fails.
void denoise_image(Image& image, const DenoiseOptions& options, const std::string& source = "the image");
