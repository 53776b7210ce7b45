// The input of fuzz_render (fuzz/fuzz_render.cpp) and how it is rendered, shared with the regression test
// that renders its findings again (tests/fuzz_regression_test.cpp).
//
// Input format: text. Up to the first separator line it is the scene, written to scene.json. A separator
// is a line "--- NAME" (NAME: 1 to 32 of [A-Za-z0-9._-], not starting with '.'); the lines after it, up
// to the next separator or the end, are the file NAME beside the scene. For example
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
// Beside the scene there are also m.obj (a unit cube), tex.png (2x2, sRGB) and env.exr (4x2, linear,
// values above 1), unless the input's files replace them.
//
// The render is tiny: camera.width and camera.height are clamped to at most 8, render.spp to 1 and
// render.max_depth to 3. Values are only ever lowered: a 0 that the loader let through reaches render().
#pragma once
#include <algorithm>
#include <cmath>
#include <cstring>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <string_view>
#include <system_error>
#include <vector>

#include "fuzz/fuzz_common.h"
#include "runtime/errors.h"
#include "runtime/image_io.h"
#include "runtime/renderer.h"
#include "scene/device_scene.h"
#include "scene/scene_description.h"

namespace fuzz {

constexpr uint32_t kRenderMaxSide = 8, kRenderMaxSpp = 1, kRenderMaxDepth = 3;

struct InputFile {
  std::string name, text;
};

inline bool valid_input_file_name(std::string_view name) {
  if (name.empty() || name.size() > 32 || name[0] == '.') return false;
  return std::all_of(name.begin(), name.end(), [](char c) {
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '.' || c == '_' || c == '-';
  });
}

// The scene (named scene.json) and the files after it.
inline std::vector<InputFile> split_render_input(std::string_view input) {
  std::vector<InputFile> files{{"scene.json", ""}};
  size_t start = 0;  // of the current file's text
  for (size_t line = 0; line <= input.size();) {
    size_t end = input.find('\n', line);
    if (end == std::string_view::npos) end = input.size();
    std::string_view text = input.substr(line, end - line);
    if (text.substr(0, 4) == "--- " && valid_input_file_name(text.substr(4))) {
      // The newline before the separator belongs to the separator.
      files.back().text = std::string(input.substr(start, line > start ? line - 1 - start : 0));
      files.push_back({std::string(text.substr(4)), ""});
      start = std::min(end + 1, input.size());
    }
    line = end + 1;
  }
  files.back().text = std::string(input.substr(start));
  return files;
}

// Where the scene of an input ends: at the newline before its first separator line, as split_render_input
// splits it (a separator on the first line, an empty scene, is not looked for).
inline size_t scene_end(std::string_view input) {
  for (size_t end = 0;; ++end) {
    end = input.find("\n--- ", end);
    if (end == std::string_view::npos) return input.size();
    size_t line_end = input.find('\n', end + 1);
    if (valid_input_file_name(input.substr(end + 5, (line_end == std::string_view::npos ? input.size() : line_end) - end - 5)))
      return end;
  }
}

// m.obj, tex.png and env.exr, made once per process (in a directory of their own).
inline const std::vector<InputFile>& fixed_render_files() {
  static const std::vector<InputFile> files = [] {
    const std::filesystem::path dir = scratch().dir();
    auto read = [](const std::filesystem::path& path) {
      std::ifstream in(path, std::ios::binary);
      return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
    };
    Image tex;
    tex.width = tex.height = 2;
    tex.rgb = {1, 0, 0, 0, 1, 0, 0, 0, 1, 0.5f, 0.5f, 0.5f};
    write_png((dir / "tex.png").string(), tex);
    Image env;
    env.width = 4;
    env.height = 2;
    env.rgb = {4, 4, 4, 0, 0, 0, 1, 2, 3, 0.5f, 0.5f, 0.5f, 0, 0, 0, 100, 50, 25, 0.25f, 0.25f, 0.25f, 1, 1, 1};
    write_exr((dir / "env.exr").string(), env);
    return std::vector<InputFile>{{"m.obj", kCubeObj}, {"tex.png", read(dir / "tex.png")}, {"env.exr", read(dir / "env.exr")}};
  }();
  return files;
}

// Empties dir and writes the fixed files, then the input's files, then the scene; returns the scene's path.
// RuntimeFailure if a file cannot be written.
inline std::string write_render_input(const std::vector<InputFile>& files, const std::filesystem::path& dir) {
  std::error_code ec;
  std::filesystem::remove_all(dir, ec);
  std::filesystem::create_directories(dir, ec);
  if (ec) throw RuntimeFailure("cannot make " + dir.string() + ": " + ec.message());
  auto write = [&](const InputFile& f) {
    std::ofstream out(dir / f.name, std::ios::binary | std::ios::trunc);
    if (!out.write(f.text.data(), std::streamsize(f.text.size()))) throw RuntimeFailure("cannot write " + f.name);
  };
  for (const InputFile& f : fixed_render_files()) write(f);
  for (size_t i = 1; i < files.size(); ++i) write(files[i]);
  write(files[0]);
  return (dir / files[0].name).string();
}

// Makes the film tiny, and the render options as `pathcl render` takes them from the scene, clamped.
inline RenderOptions tiny_render(SceneDescription& scene) {
  scene.camera.width = std::min(scene.camera.width, kRenderMaxSide);
  scene.camera.height = std::min(scene.camera.height, kRenderMaxSide);
  RenderOptions options;
  options.spp = std::min(scene.render.spp, kRenderMaxSpp);
  options.max_depth = std::min(scene.render.max_depth, kRenderMaxDepth);
  options.seed = scene.render.seed;
  options.sampler = scene.render.sampler;
  return options;
}

// An OpenCL failure that is a reported lack of memory: an expected outcome of a large scene.
inline bool reported_out_of_memory(const std::string& message) {
  for (const char* m : {"CL_MEM_OBJECT_ALLOCATION_FAILURE", "CL_OUT_OF_HOST_MEMORY", "the render needs ",
                        " allows in one allocation "})
    if (message.find(m) != std::string::npos) return true;
  return false;
}

// What the render may not produce, or "": a film of the wrong size or spp or with a value that is not
// finite, or NaN, infinite or negative samples counted by the kernel.
inline std::string render_problem(const RenderResult& r, const DeviceScene& scene, const RenderOptions& options) {
  const Film& f = r.film;
  const size_t pixels = size_t(scene.header.width) * scene.header.height;
  if (f.width != scene.header.width || f.height != scene.header.height || f.mean.size() != 3 * pixels ||
      f.variance.size() != 3 * pixels || f.even_mean.size() != 3 * pixels || f.odd_mean.size() != 3 * pixels ||
      f.words.size() != PC_RADIANCE_WORDS * pixels)
    return "the film's size differs from the camera's";
  if (f.spp != options.spp) return "the film has " + std::to_string(f.spp) + " spp, not " + std::to_string(options.spp);
  if (r.nan_samples || r.inf_samples || r.negative_samples)
    return "the kernel counted " + std::to_string(r.nan_samples) + " NaN, " + std::to_string(r.inf_samples) +
           " infinite and " + std::to_string(r.negative_samples) + " negative samples";
  for (const std::vector<float>* v : {&f.mean, &f.variance, &f.even_mean, &f.odd_mean})
    for (float x : *v)
      if (!std::isfinite(x)) return "a film value is not finite";
  for (uint32_t word : f.words) {  // the path integrator's accumulators (floats)
    float a;
    std::memcpy(&a, &word, sizeof a);
    if (!std::isfinite(a)) return "a film accumulator is not finite";
  }
  return "";
}

}  // namespace fuzz
