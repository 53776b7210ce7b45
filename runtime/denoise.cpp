#include "runtime/denoise.h"

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <type_traits>
#include <utility>

#include <dlfcn.h>
#include <glob.h>

#include "runtime/errors.h"

// AddressSanitizer's build: gcc says so with __SANITIZE_ADDRESS__, clang 14 only through __has_feature.
#if defined(__SANITIZE_ADDRESS__)
#define PATHCL_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define PATHCL_ASAN 1
#endif
#endif

namespace {

// The parts of OIDN 2.x's C API that pathcl calls, declared here rather than taken from
// OpenImageDenoise/oidn.h: the library is loaded at run time and its headers are not installed. The
// values are those of oidn.h in OIDN 2.x (OIDNDeviceType, OIDNFormat, OIDNError, OIDNQuality); the C
// enums are passed as int, which they are in the x86-64 and AArch64 C ABIs.
struct OIDNDeviceImpl;
struct OIDNFilterImpl;
using OIDNDevice = OIDNDeviceImpl*;
using OIDNFilter = OIDNFilterImpl*;
constexpr int OIDN_DEVICE_TYPE_CPU = 1, OIDN_DEVICE_TYPE_SYCL = 2, OIDN_DEVICE_TYPE_CUDA = 3, OIDN_DEVICE_TYPE_HIP = 4,
              OIDN_DEVICE_TYPE_METAL = 5;
constexpr int OIDN_FORMAT_FLOAT3 = 3;
constexpr int OIDN_ERROR_NONE = 0;
constexpr int OIDN_QUALITY_FAST = 4, OIDN_QUALITY_BALANCED = 5, OIDN_QUALITY_HIGH = 6;

struct OidnApi {
  void* library = nullptr;
  std::string error;  // why it is not there, with how to get it
  OIDNDevice (*newDevice)(int type) = nullptr;
  void (*commitDevice)(OIDNDevice) = nullptr;
  int (*getDeviceError)(OIDNDevice, const char** message) = nullptr;
  int (*getDeviceInt)(OIDNDevice, const char* name) = nullptr;
  void (*releaseDevice)(OIDNDevice) = nullptr;
  int (*getNumPhysicalDevices)() = nullptr;
  int (*getPhysicalDeviceInt)(int id, const char* name) = nullptr;
  const char* (*getPhysicalDeviceString)(int id, const char* name) = nullptr;
  OIDNFilter (*newFilter)(OIDNDevice, const char* type) = nullptr;
  void (*setSharedFilterImage)(OIDNFilter, const char* name, void* data, int format, size_t width, size_t height,
                               size_t byte_offset, size_t pixel_byte_stride, size_t row_byte_stride) = nullptr;
  void (*setFilterBool)(OIDNFilter, const char* name, bool value) = nullptr;
  void (*setFilterInt)(OIDNFilter, const char* name, int value) = nullptr;
  void (*commitFilter)(OIDNFilter) = nullptr;
  void (*executeFilter)(OIDNFilter) = nullptr;
  void (*releaseFilter)(OIDNFilter) = nullptr;
};

const char* const how_to_get_it =
    "denoising needs Intel Open Image Denoise 2.x: scripts/setup installs it from PyPI's pyoidn into "
    "build/oidn-venv, or set PATHCL_OIDN_LIBRARY to the path of a libOpenImageDenoise.so.2";

// The libraries the search finds, in order (see runtime/denoise.h).
std::vector<std::string> library_candidates() {
  if (const char* path = std::getenv("PATHCL_OIDN_LIBRARY"); path && *path)
    return {path};  // a library named by the user, and no other: a fallback would hide a wrong path
  std::vector<std::string> found;
#ifdef PATHCL_OIDN_VENV
  // pyoidn's wheel keeps the library and the CPU device module it loads beside each other.
  std::string pattern = std::string(PATHCL_OIDN_VENV) + "/lib/python3*/site-packages/pyoidn/oidn/lib/libOpenImageDenoise.so.2*";
  glob_t g{};
  if (glob(pattern.c_str(), 0, nullptr, &g) == 0)
    for (size_t i = 0; i < g.gl_pathc; ++i) found.push_back(g.gl_pathv[i]);  // sorted: .so.2 before .so.2.5.1
  globfree(&g);
#endif
  found.push_back("libOpenImageDenoise.so.2");
  return found;
}

OidnApi load_oidn() {
  OidnApi api;
  std::string tried, loaded;
  for (const std::string& path : library_candidates()) {
    // OIDN's CPU device needs oneTBB's libtbb.so.12: pathcl has Debian's loaded already (scene/ uses it),
    // and the device binds to that one rather than to the wheel's copy; every symbol it needs is there.
    api.library = dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);
    loaded = path;
    if (api.library) break;
    const char* e = dlerror();
    tried += (tried.empty() ? "" : "; ") + std::string(e ? e : path + ": cannot load");
  }
  if (!api.library) {
    api.error = std::string(how_to_get_it) + " (not found: " + tried + ")";
    return api;
  }
  std::string missing;
  auto get = [&](auto& function, const char* name) {
    function = reinterpret_cast<std::remove_reference_t<decltype(function)>>(dlsym(api.library, name));
    if (!function) missing += (missing.empty() ? "" : ", ") + std::string(name);
  };
  get(api.newDevice, "oidnNewDevice");
  get(api.commitDevice, "oidnCommitDevice");
  get(api.getDeviceError, "oidnGetDeviceError");
  get(api.getDeviceInt, "oidnGetDeviceInt");
  get(api.releaseDevice, "oidnReleaseDevice");
  get(api.getNumPhysicalDevices, "oidnGetNumPhysicalDevices");
  get(api.getPhysicalDeviceInt, "oidnGetPhysicalDeviceInt");
  get(api.getPhysicalDeviceString, "oidnGetPhysicalDeviceString");
  get(api.newFilter, "oidnNewFilter");
  get(api.setSharedFilterImage, "oidnSetSharedFilterImage");
  get(api.setFilterBool, "oidnSetFilterBool");
  get(api.setFilterInt, "oidnSetFilterInt");
  get(api.commitFilter, "oidnCommitFilter");
  get(api.executeFilter, "oidnExecuteFilter");
  get(api.releaseFilter, "oidnReleaseFilter");
  if (!missing.empty()) api.error = std::string(how_to_get_it) + " (" + loaded + " is not: it lacks " + missing + ")";
#ifdef PATHCL_ASAN
  // OIDN's device starts oneTBB, which opens libtbbbind with RTLD_DEEPBIND: ASan's runtime refuses that by
  // ending the process (google/sanitizers issue 611), so a sanitizer build finds the library and stops there.
  else
    api.error = std::string(how_to_get_it) + " (" + loaded + " loads, but this build of pathcl has AddressSanitizer, "
                "whose runtime cannot run it: its oneTBB opens libtbbbind with RTLD_DEEPBIND; build/ denoises)";
#endif
  if (!api.error.empty()) {
    dlclose(api.library);
    api.library = nullptr;
  }
  return api;
}

// Loaded once per process (thread-safe static initialisation); never unloaded.
const OidnApi& oidn() {
  static const OidnApi api = load_oidn();
  if (!api.library) throw RuntimeFailure(api.error);
  return api;
}

// Throws RuntimeFailure with OIDN's message if the device holds an error (also for a device that failed
// to start: OIDN answers for a null device too).
void check(const OidnApi& api, OIDNDevice device, const char* what) {
  const char* message = nullptr;
  if (api.getDeviceError(device, &message) != OIDN_ERROR_NONE)
    throw RuntimeFailure(std::string("Intel Open Image Denoise: ") + what + ": " + (message ? message : "unknown error"));
}

// A committed CPU device of OIDN 2.x, released at the end of its scope.
struct Device {
  const OidnApi& api;
  OIDNDevice device;
  explicit Device(const OidnApi& a) : api(a), device(a.newDevice(OIDN_DEVICE_TYPE_CPU)) {
    try {
      check(api, device, "cannot create the CPU device");
      api.commitDevice(device);
      check(api, device, "cannot start the CPU device");
      // Enum values and the ABI may change with a major version.
      int major = api.getDeviceInt(device, "versionMajor");
      if (major != 2)
        throw RuntimeFailure(std::string(how_to_get_it) + " (the library found is version " + std::to_string(major) + ")");
    } catch (...) {
      if (device) api.releaseDevice(device);  // the destructor of a half-made object does not run
      throw;
    }
  }
  ~Device() {
    if (device) api.releaseDevice(device);
  }
  Device(const Device&) = delete;
  Device& operator=(const Device&) = delete;
  std::string version() const {
    int v = api.getDeviceInt(device, "version");  // major * 10000 + minor * 100 + patch
    return std::to_string(v / 10000) + "." + std::to_string(v / 100 % 100) + "." + std::to_string(v % 100);
  }
  // The device's type and the name of the physical device of that type, as OIDN's documented parameters
  // ("type"; the physical device's "type" and "name") give them: "CPU: Intel(R) Xeon(R) Processor". OIDN 2.5
  // has no parameter for the instruction set its CPU kernels use (only its verbose console output shows it).
  std::string description() const {
    int type = api.getDeviceInt(device, "type");
    std::string text = type == OIDN_DEVICE_TYPE_CPU     ? "CPU"
                       : type == OIDN_DEVICE_TYPE_SYCL  ? "SYCL"
                       : type == OIDN_DEVICE_TYPE_CUDA  ? "CUDA"
                       : type == OIDN_DEVICE_TYPE_HIP   ? "HIP"
                       : type == OIDN_DEVICE_TYPE_METAL ? "Metal"
                                                        : "device type " + std::to_string(type);
    for (int i = 0, n = api.getNumPhysicalDevices(); i < n; ++i)
      if (api.getPhysicalDeviceInt(i, "type") == type) {
        const char* name = api.getPhysicalDeviceString(i, "name");
        if (name && *name) text += std::string(": ") + name;
        break;
      }
    return text;
  }
};

// An "RT" filter, released at the end of its scope.
struct Filter {
  const OidnApi& api;
  OIDNFilter filter;
  explicit Filter(const Device& d) : api(d.api), filter(d.api.newFilter(d.device, "RT")) { check(api, d.device, "cannot create the RT filter"); }
  ~Filter() {
    if (filter) api.releaseFilter(filter);
  }
  Filter(const Filter&) = delete;
  Filter& operator=(const Filter&) = delete;
  // A shared image: OIDN's CPU device works on the vector's memory, without a copy. Inputs are only read
  // (so the const_cast is safe); the output is written.
  void image(const char* name, const std::vector<float>& pixels, uint32_t width, uint32_t height) {
    api.setSharedFilterImage(filter, name, const_cast<float*>(pixels.data()), OIDN_FORMAT_FLOAT3, width, height, 0, 0, 0);
  }
  void set(const char* name, bool value) { api.setFilterBool(filter, name, value); }
  void run(const Device& d, int quality, const char* what) {
    api.setFilterInt(filter, "quality", quality);
    api.commitFilter(filter);
    check(api, d.device, what);
    api.executeFilter(filter);
    check(api, d.device, what);
  }
};

// OIDN's prefiltering of one auxiliary image (its documentation, "Denoising with prefiltering"): a copy
// denoised in place by an RT filter given only that image, as `name` ("albedo" or "normal"), and the
// output.
std::vector<float> prefiltered(const Device& device, const char* name, const std::vector<float>& pixels,
                               uint32_t width, uint32_t height, int quality) {
  std::vector<float> clean = pixels;
  Filter f(device);
  f.image(name, clean, width, height);
  f.image("output", clean, width, height);
  f.run(device, quality, ("prefiltering the " + std::string(name)).c_str());
  return clean;
}

int quality_value(const std::string& quality) {
  if (quality == "high") return OIDN_QUALITY_HIGH;
  if (quality == "balanced") return OIDN_QUALITY_BALANCED;
  if (quality == "fast") return OIDN_QUALITY_FAST;
  throw UsageError("denoiser quality \"" + quality + "\": expected high, balanced or fast");
}

// The channels of a guide layer in this order; where the layer or one of its channels is missing, empty,
// and what is missing is added to *missing.
std::vector<float> guide_layer(const Image& image, const std::string& name, const std::vector<std::string>& channels,
                               std::string* missing) {
  std::string all;
  for (const std::string& c : channels) all += (all.empty() ? "" : ", ") + name + "." + c;
  auto add = [&](const std::string& what) { *missing += (missing->empty() ? "" : " and ") + what; };
  const ImageLayer* layer = find_layer(image, name);
  if (!layer) {
    add("no layer " + name + " (" + all + ")");
    return {};
  }
  std::vector<size_t> index;
  for (const std::string& c : channels) {
    auto it = std::find(layer->channels.begin(), layer->channels.end(), c);
    if (it == layer->channels.end()) {
      add("no " + name + "." + c + " in the layer " + name + " (" + all + ")");
      return {};
    }
    index.push_back(size_t(it - layer->channels.begin()));
  }
  size_t pixels = size_t(image.width) * image.height, n = layer->channels.size();
  std::vector<float> out(pixels * channels.size());
  for (size_t p = 0; p < pixels; ++p)
    for (size_t c = 0; c < index.size(); ++c) out[p * index.size() + c] = layer->values[p * n + index[c]];
  return out;
}

// Puts the layer into the image, in place of one of the same name.
void set_layer(Image& image, ImageLayer layer) {
  auto old = std::find_if(image.layers.begin(), image.layers.end(), [&](const ImageLayer& l) { return l.name == layer.name; });
  if (old != image.layers.end())
    *old = std::move(layer);
  else
    image.layers.push_back(std::move(layer));
}

}  // namespace

bool denoiser_available(std::string* why) {
  try {
    Device device(oidn());
    return true;
  } catch (const std::exception& e) {
    if (why) *why = e.what();
    return false;
  }
}

DenoiseResult denoise(uint32_t width, uint32_t height, const std::vector<float>& rgb, const std::vector<float>* albedo,
                      const std::vector<float>* normal, const DenoiseOptions& options) {
  int quality = quality_value(options.quality);
  size_t floats = size_t(width) * height * 3;
  for (auto [buffer, name] : {std::pair{&rgb, "image"}, {albedo, "albedo"}, {normal, "normal"}})
    if (buffer && buffer->size() != floats)
      throw UsageError(std::string("denoise: the ") + name + " holds " + std::to_string(buffer->size()) +
                       " floats where " + std::to_string(width) + " x " + std::to_string(height) + " x 3 need " +
                       std::to_string(floats));
  if (!albedo) normal = nullptr;  // OIDN's RT filter takes a normal only beside an albedo
  auto start = std::chrono::steady_clock::now();
  Device device(oidn());
  DenoiseResult result;
  result.library_version = device.version();
  result.device = device.description();
  result.used_albedo = albedo != nullptr;
  result.used_normal = normal != nullptr;
  result.rgb.assign(floats, 0.0f);
  // OIDN's prefiltering: each auxiliary image is denoised first (prefiltered), and the beauty's filter
  // takes them as noise-free (cleanAux). OIDN only has clean-feature weights for albedo and normal together.
  bool prefilter = albedo && normal && options.clean_aux;
  std::vector<float> clean_albedo, clean_normal;
  if (prefilter) {
    clean_albedo = prefiltered(device, "albedo", *albedo, width, height, quality);
    clean_normal = prefiltered(device, "normal", *normal, width, height, quality);
    albedo = &clean_albedo;
    normal = &clean_normal;
  }
  Filter f(device);
  f.image("color", rgb, width, height);
  if (albedo) f.image("albedo", *albedo, width, height);
  if (normal) f.image("normal", *normal, width, height);
  f.image("output", result.rgb, width, height);
  f.set("hdr", true);
  f.set("cleanAux", prefilter);
  f.run(device, quality, "denoising");
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

void denoise_image(Image& image, const DenoiseOptions& options, const std::string& source) {
  // An image denoised before: its raw layer is the render, and it is what is denoised again (the RGB is
  // already filtered; OIDN is trained on Monte Carlo noise, and the raw layer must stay the render's).
  const ImageLayer* raw = find_layer(image, "raw");
  if (raw && (raw->integer || raw->channels != std::vector<std::string>{"R", "G", "B"})) {
    std::string channels;
    for (const std::string& c : raw->channels) channels += (channels.empty() ? "raw." : ", raw.") + c;
    throw UsageError(source + ": the layer \"raw\" has the " + (raw->integer ? "integer " : "") + "channels " +
                     channels + ", expected the float channels raw.R, raw.G, raw.B (the beauty before denoising)");
  }
  const bool denoised_before = raw != nullptr;
  if (options.use_normal && !options.use_albedo)
    throw UsageError("denoising " + source + ": a normal guides Open Image Denoise only beside an albedo");
  // Every guide asked for must be there: a quiet fall-back to fewer guides gives a worse image than the
  // command line asked for, with nothing but a header attribute to say so.
  std::vector<float> albedo, normal;
  std::string missing;
  if (options.use_albedo) albedo = guide_layer(image, "albedo", {"R", "G", "B"}, &missing);
  if (options.use_normal) normal = guide_layer(image, "normal", {"X", "Y", "Z"}, &missing);
  if (!missing.empty())
    throw UsageError(source + ": " + missing + " to guide the denoiser: render the guides with --aov albedo,normal " +
                     "(render --denoise does), or denoise with fewer: " +
                     (albedo.empty() ? "" : "--aux albedo (the albedo alone) or ") + "--no-aux (the colour alone)");
  DenoiseResult r = denoise(image.width, image.height, denoised_before ? raw->values : image.rgb,
                            albedo.empty() ? nullptr : &albedo, normal.empty() ? nullptr : &normal, options);
  if (!denoised_before) set_layer(image, {"raw", {"R", "G", "B"}, std::move(image.rgb), false});
  image.rgb = std::move(r.rgb);
  // The variance is the raw beauty's: beside it, and not at the top level, where `pathcl compare` would
  // z-test the denoised beauty against it. The denoiser gives no variance of its own. (An image denoised
  // before with a top-level variance was written by an older pathcl: that variance is the raw layer's too.)
  if (!image.variance.empty()) {
    if (!denoised_before || !find_layer(image, "raw.variance"))
      set_layer(image, {"raw.variance", {"R", "G", "B"}, std::move(image.variance), false});
    image.variance.clear();
  }
  // The render's determinism ("bitwise": the same bits on any conformant OpenCL device) is the raw
  // layer's; the denoised beauty's is the denoiser's (kDenoisedDeterminism).
  auto& attributes = image.attributes;
  auto determinism = attributes.find("determinism");
  bool render_determinism = determinism != attributes.end() && determinism->second != kDenoisedDeterminism;
  if (!denoised_before) attributes.erase("raw.determinism");
  if (render_determinism && !attributes.count("raw.determinism")) attributes["raw.determinism"] = determinism->second;
  attributes["determinism"] = kDenoisedDeterminism;
  attributes["denoiser"] = "Intel Open Image Denoise " + r.library_version;
  attributes["denoiser_device"] = r.device;
  attributes["denoiser_quality"] = options.quality;
  attributes["denoiser_aux"] = r.used_normal ? "albedo,normal" : r.used_albedo ? "albedo" : "none";
}
