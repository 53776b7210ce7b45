// libFuzzer target: a whole scene along the path of `pathcl render`: load_scene (JSON, OBJ and MTL files,
// textures, CGAL clean-up), build_device_scene (BVH, lights, flattening) and, whenever it loads, render()
// of runtime/renderer.h on an OpenCL device, at most 8x8 pixels, 1 spp and depth 3. Run by scripts/fuzz.
//
// Input format (fuzz/render_input.h): the scene JSON, then any files it names, each after a line
// "--- NAME". For example
//
//   {"camera": {"position": [0, 0, 3], "look_at": [0, 0, 0], "width": 8, "height": 8},
//    "materials": {"m": {"type": "diffuse"}},
//    "shapes": [{"type": "mesh", "file": "mesh.obj", "material": "m", "emission": [1, 1, 1]}]}
//   --- mesh.obj
//   v 0 0 0
//   v 1 0 0
//   v 0 1 0
//   f 1 2 3
//
// The scene's directory is emptied before every input; m.obj (a unit cube), tex.png and env.exr are
// there too unless the input replaces them. Inputs with an OBJ file of more than 500 polygons or a polygon
// of more than 64 vertices are skipped (CGAL's triangulation is cubic in a polygon's size). The film is
// clamped to 8x8, spp to 1, max_depth to 3 (only lowered, never raised).
//
// Findings (abort, so that libFuzzer keeps the input): crashes and sanitizer reports; any exception but
// SceneError and UsageError (the exit-2 class of `pathcl`), RuntimeFailure included, except a reported
// out-of-memory (fuzz::reported_out_of_memory); a film of the wrong size or spp or with a value that is
// not finite; NaN, infinite or negative samples counted by the kernel (fuzz::render_problem).
//
// The OpenCL context lives for the whole process with keep_programs set (runtime/device.h), so each
// specialised kernel is built (or loaded from the PATHCL_KERNEL_CACHE binary cache) once per process and
// an input costs milliseconds; PATHCL_FUZZ_ALL_FEATURES=1 uses the one unspecialised kernel instead
// (short runs: scripts/fuzz). The device is $PATHCL_TEST_DEVICE, by default "pthread" (PoCL's CPU
// device). PATHCL_FUZZ_VERBOSE=1 prints what became of each input (for looking at a corpus).
#include <csignal>
#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <filesystem>
#include <iterator>
#include <set>
#include <string>
#include <string_view>
#include <vector>

#include "fuzz/fuzz_common.h"
#include "fuzz/render_input.h"
#include "fuzz/scene_mutator.h"
#include "runtime/device.h"
#include "runtime/errors.h"
#include "runtime/renderer.h"
#include "scene/device_scene_build.h"
#include "scene/scene_description.h"
#include "scene/scene_error.h"

namespace {

constexpr size_t kMaxPolygons = 500, kMaxPolygonVertices = 64;

ClContext& device() {
  // Never destroyed: PoCL's threads may outlive static destructors at exit. Reachable, so not a leak.
  static ClContext* cl = [] {
    const char* selector = std::getenv("PATHCL_TEST_DEVICE");
    auto* context = new ClContext(select_device(selector && *selector ? selector : "pthread"));
    context->keep_programs = true;
    return context;
  }();
  return *cl;
}

bool verbose() {
  static const bool on = [] {
    const char* v = std::getenv("PATHCL_FUZZ_VERBOSE");
    return v && *v && std::string(v) != "0";
  }();
  return on;
}

// PATHCL_FUZZ_ALL_FEATURES=1: render with the unspecialised kernel (`pathcl render --all-features`), built
// once, instead of one specialised to each feature set (seconds to compile each): for short runs.
bool all_features() {
  static const bool on = [] {
    const char* v = std::getenv("PATHCL_FUZZ_ALL_FEATURES");
    return v && *v && std::string(v) != "0";
  }();
  return on;
}

// What became of the inputs, printed at exit: how many got how far, where the time went, and how the
// kernels were obtained.
struct Counts {
  uint64_t inputs = 0, loaded = 0, rendered = 0, built = 0;
  double load_s = 0, render_s = 0, build_s = 0;  // loading and flattening (rejected inputs too); render()
  std::set<uint32_t> features;                   // the feature sets rendered
} counts;

void print_counts() {
  std::fprintf(stderr,
               "pathcl fuzz_render: %llu inputs, %llu loaded, %llu rendered; %.1f s loading, %.1f s rendering, "
               "%.1f s of it compiling %llu kernels; %zu feature sets (%s)\n",
               (unsigned long long)counts.inputs, (unsigned long long)counts.loaded,
               (unsigned long long)counts.rendered, counts.load_s, counts.render_s, counts.build_s,
               (unsigned long long)counts.built, counts.features.size(),
               all_features() ? "all with the all-features kernel" : "a specialised kernel each");
}

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// The last inputs that rendered: the mutator starts from one of them instead of an input whose scene is
// not JSON (libFuzzer keeps those in the corpus for the JSON parser's error paths, and a byte-level
// mutation can make one at any step of a chain of mutations).
std::vector<std::string> rendered_inputs;
size_t next_rendered = 0, remembered = 0;
constexpr size_t kRenderedInputs = 64;

// Copied into strings whose capacity is allocated up front: an input that allocates more than it frees
// makes libFuzzer run it again and look for leaks, which costs a scan of the whole heap.
void remember_rendered(const uint8_t* data, size_t size) {
  if (rendered_inputs.empty()) {
    rendered_inputs.resize(kRenderedInputs);
    for (std::string& s : rendered_inputs) s.reserve(fuzz::kMaxInputBytes);
  }
  rendered_inputs[next_rendered].assign(reinterpret_cast<const char*>(data), size);
  next_rendered = (next_rendered + 1) % kRenderedInputs;
  remembered = std::min(remembered + 1, kRenderedInputs);
}

[[noreturn]] void finding(const std::string& what) {
  std::fprintf(stderr, "pathcl fuzz_render: %s\n", what.c_str());
  std::abort();
}

// Whether the OBJ files are small enough for CGAL to clean quickly.
bool meshes_small_enough(const std::vector<fuzz::InputFile>& files, const std::filesystem::path& dir) {
  for (const fuzz::InputFile& file : files) {
    if (file.name.size() < 4 || file.name.compare(file.name.size() - 4, 4, ".obj") != 0) continue;
    try {
      const PolygonSoup soup = load_obj((dir / file.name).string());
      if (soup.polygons.size() > kMaxPolygons) return false;
      for (const auto& polygon : soup.polygons)
        if (polygon.size() > kMaxPolygonVertices) return false;
    } catch (const SceneError&) {
      // The scene's loading will say so, if the scene uses it.
    }
  }
  return true;
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  try {
    fuzz::fixed_render_files();
    // PoCL's LLVM installs its signal handlers when PoCL starts; left there, libFuzzer (which installs its
    // own after this function) installs none, and an abort() (a finding, an uncaught exception) would end
    // the process without saving the input. Put back what was there before (fuzz/CMakeLists.txt); PoCL's
    // SIGFPE handler stays (it makes a kernel's integer division by zero harmless, as OpenCL requires).
    const int crash_signals[] = {SIGABRT, SIGSEGV, SIGBUS, SIGILL, SIGTRAP, SIGSYS, SIGXCPU, SIGXFSZ, SIGQUIT, SIGINT, SIGTERM};
    struct sigaction before[std::size(crash_signals)];
    for (size_t i = 0; i < std::size(crash_signals); ++i) sigaction(crash_signals[i], nullptr, &before[i]);
    device();
    for (size_t i = 0; i < std::size(crash_signals); ++i) sigaction(crash_signals[i], &before[i], nullptr);
    std::atexit(print_counts);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "pathcl fuzz_render: cannot set up: %s\n", e.what());
    std::exit(1);
  }
  return 0;
}

extern "C" size_t LLVMFuzzerMutate(uint8_t* data, size_t size, size_t max_size);

// Most mutations change the scene's JSON structurally (fuzz/scene_mutator.h); one in six is libFuzzer's
// own on the bytes of the files after the scene (OBJ, MTL), one in twenty on the bytes of the whole input.
// An input whose scene is not JSON is replaced by one that rendered lately, three times in four, before
// the scene is changed. Crossing over swaps members of two scenes.
extern "C" size_t LLVMFuzzerCustomMutator(uint8_t* data, size_t size, size_t max_size, unsigned seed) {
  const unsigned choice = seed % 60;
  seed /= 60;
  if (choice >= 13) {
    if (size_t n = fuzz::mutate_scene(data, size, max_size, seed)) return n;
    if (remembered > 0 && seed % 4 != 0) {
      const std::string& other = rendered_inputs[(seed / 4) % remembered];
      if (other.size() <= max_size) {
        std::memcpy(data, other.data(), other.size());
        if (size_t n = fuzz::mutate_scene(data, other.size(), max_size, seed)) return n;
        return other.size();
      }
    }
  }
  if (choice >= 3)
    if (size_t n = fuzz::mutate_files(data, size, max_size, LLVMFuzzerMutate)) return n;
  return LLVMFuzzerMutate(data, size, max_size);
}

extern "C" size_t LLVMFuzzerCustomCrossOver(const uint8_t* data1, size_t size1, const uint8_t* data2, size_t size2,
                                            uint8_t* out, size_t max_size, unsigned seed) {
  return fuzz::cross_scenes(data1, size1, data2, size2, out, max_size, seed);
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size > fuzz::kMaxInputBytes) return 0;
  counts.inputs++;
  const std::filesystem::path dir = fuzz::scratch().dir() / "render";
  const std::vector<fuzz::InputFile> files =
      fuzz::split_render_input(std::string_view(reinterpret_cast<const char*>(data), size));
  std::string path;
  try {
    path = fuzz::write_render_input(files, dir);
  } catch (const RuntimeFailure& e) {
    finding(e.what());  // the harness, not the input
  }
  if (!meshes_small_enough(files, dir)) return 0;

  std::string stage = "load";
  auto start = std::chrono::steady_clock::now();
  try {
    SceneDescription scene = load_scene(path);
    const RenderOptions options = fuzz::tiny_render(scene);
    stage = "build";
    const DeviceScene device_scene = build_device_scene(scene);
    counts.loaded++;
    counts.load_s += seconds_since(start);
    stage = "render";
    RenderOptions run = options;
    run.all_features = all_features();
    start = std::chrono::steady_clock::now();
    const RenderResult result = render(device(), device_scene, run);
    counts.render_s += seconds_since(start);
    counts.rendered++;
    counts.features.insert(device_scene.features);
    if (!result.kernel_from_cache) {
      counts.built++;
      counts.build_s += result.kernel_build_ms * 1e-3;
    }
    const std::string problem = fuzz::render_problem(result, device_scene, options);
    if (!problem.empty()) finding(problem);
    remember_rendered(data, size);
    if (verbose())
      std::fprintf(stderr, "pathcl fuzz_render: rendered %ux%u, features 0x%x, kernel %s in %.1f ms\n",
                   result.film.width, result.film.height, device_scene.features,
                   result.kernel_from_cache ? "cached" : "built", result.kernel_build_ms);
  } catch (const SceneError& e) {
    if (verbose()) std::fprintf(stderr, "pathcl fuzz_render: %s: SceneError: %s\n", stage.c_str(), e.what());
  } catch (const UsageError& e) {
    if (verbose()) std::fprintf(stderr, "pathcl fuzz_render: %s: UsageError: %s\n", stage.c_str(), e.what());
  } catch (const RuntimeFailure& e) {
    if (!fuzz::reported_out_of_memory(e.what())) finding(stage + ": RuntimeFailure: " + e.what());
    if (verbose()) std::fprintf(stderr, "pathcl fuzz_render: %s: out of memory: %s\n", stage.c_str(), e.what());
  } catch (const std::exception& e) {
    finding(stage + ": unexpected exception: " + e.what());
  }
  if (stage != "render") counts.load_s += seconds_since(start);
  return 0;
}
