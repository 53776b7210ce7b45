#include "test_support.h"

#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <stdexcept>

#include <glm/geometric.hpp>
#include <gtest/gtest.h>
#include <stb_image_write.h>

#include "scene/scene_error.h"

namespace fs = std::filesystem;

ClContext& test_device() {
  static std::unique_ptr<ClContext> cl;
  if (!cl) {
    const char* selector = std::getenv("PATHCL_TEST_DEVICE");
    cl = std::make_unique<ClContext>(select_device(selector ? selector : ""));
    // Tests render the same programs again and again: each kept on the context, not loaded from the cache
    // for every render (runtime/device.h). The loads themselves are tested by cli_test's cache tests.
    cl->keep_programs = true;
  }
  return *cl;
}

const KernelProgram& sampling_test_program() {
  static KernelProgram program = build_kernel_program(test_device(), "tests_sampling.cl", kernel_options(kFeatureAll));
  return program;
}

BvhWidthScope::BvhWidthScope(uint32_t width) {
  if (const char* old = std::getenv("PATHCL_BVH_WIDTH")) saved = old, had = true;
  setenv("PATHCL_BVH_WIDTH", std::to_string(width).c_str(), 1);
}

BvhWidthScope::~BvhWidthScope() {
  if (had)
    setenv("PATHCL_BVH_WIDTH", saved.c_str(), 1);
  else
    unsetenv("PATHCL_BVH_WIDTH");
}

std::string temp_dir() {
  static std::string dir;
  if (dir.empty()) {
    char pattern[] = "/tmp/pathcl-test-XXXXXX";
    dir = mkdtemp(pattern);
    std::atexit([] { fs::remove_all(dir); });
  }
  return dir;
}

std::string write_temp_file(const std::string& name, const std::string& text) {
  std::string path = temp_dir() + "/" + name;
  fs::create_directories(fs::path(path).parent_path());
  std::ofstream(path) << text;
  return path;
}

std::string write_temp_png(const std::string& name, int width, int height, const std::vector<unsigned char>& rgb) {
  std::string path = temp_dir() + "/" + name;
  fs::create_directories(fs::path(path).parent_path());
  int channels = width * height > 0 && rgb.size() == size_t(width) * height * 4 ? 4 : 3;  // RGBA or RGB
  if (rgb.size() != size_t(width) * height * channels ||
      !stbi_write_png(path.c_str(), width, height, channels, rgb.data(), width * channels))
    throw std::runtime_error("cannot write the test image " + path);
  return path;
}

DeviceScene load_device_scene(const std::string& path, DeviceOrigin origin) {
  // Around the world origin the scene is traced as ray files are: one flat tree (as `pathcl rays` does).
  return build_device_scene(load_scene(path), origin, origin == DeviceOrigin::world ? Instancing::flatten : Instancing::keep);
}

std::string scene_load_error(const std::string& path) {
  try {
    load_scene(path);
  } catch (const SceneError& e) {
    return e.what();
  }
  return "";
}

std::string read_text_file(const std::string& path) {
  std::stringstream ss;
  ss << std::ifstream(path).rdbuf();
  return ss.str();
}

int run_pathcl(const std::string& args, std::string* err, std::string* out) {
  std::string err_file = temp_dir() + "/stderr.txt", out_file = temp_dir() + "/stdout.txt";
  std::string command = std::string(PATHCL_BINARY) + " " + args + " >" + out_file + " 2>" + err_file;
  int status = std::system(command.c_str());
  if (err) *err = read_text_file(err_file);
  if (out) *out = read_text_file(out_file);
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

LaneComparison compare_lanes(const std::vector<uint32_t>& bits, size_t items, size_t stride, bool (*valid)(float)) {
  LaneComparison c;
  for (size_t i = 0; i < items; ++i)
    for (size_t j = 0; j < stride; ++j) {
      const uint32_t one = bits[(3 * i + 2) * stride + j];
      c.differing += (bits[3 * i * stride + j] != one) + (bits[(3 * i + 1) * stride + j] != one);
      float f;
      std::memcpy(&f, &one, sizeof f);
      c.valid += valid(f);
    }
  return c;
}

std::vector<uint32_t> run_float_lanes_test(const char* kernel, const std::vector<float>& in, size_t items, size_t stride) {
  ClContext& cl = test_device();
  ClBuffer bin = upload(cl, in), out(cl, CL_MEM_WRITE_ONLY, items * 3 * stride * sizeof(uint32_t));
  ClKernel k(sampling_test_program().kernel(kernel));
  k.arg(0, bin.mem);
  k.arg(1, out.mem);
  run_kernel(cl, k.k, items);
  return read_buffer<uint32_t>(cl, out, items * 3 * stride);
}

MeanStd mean_and_error(const std::vector<double>& values) {
  MeanStd r;
  double n = double(values.size());
  for (double v : values) r.mean += v;
  r.mean /= n;
  double var = 0;
  for (double v : values) var += (v - r.mean) * (v - r.mean);
  var /= (n - 1);
  r.std_error = std::sqrt(var / n);
  return r;
}

std::string icosphere_json(float radius, int subdivisions, bool inward) {
  const float t = (1.0f + std::sqrt(5.0f)) / 2.0f;
  std::vector<glm::vec3> v = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
                              {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  std::vector<std::array<int, 3>> f = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                                       {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                                       {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                                       {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
  for (auto& p : v) p = glm::normalize(p);
  for (int s = 0; s < subdivisions; ++s) {
    std::map<std::pair<int, int>, int> mid;
    auto midpoint = [&](int a, int b) {
      auto key = std::minmax(a, b);
      auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      v.push_back(glm::normalize(v[a] + v[b]));
      return mid[key] = int(v.size() - 1);
    };
    std::vector<std::array<int, 3>> next;
    for (auto& tri : f) {
      int a = midpoint(tri[0], tri[1]), b = midpoint(tri[1], tri[2]), c = midpoint(tri[2], tri[0]);
      next.push_back({tri[0], a, c});
      next.push_back({tri[1], b, a});
      next.push_back({tri[2], c, b});
      next.push_back({a, b, c});
    }
    f = next;
  }
  std::ostringstream out;
  out.precision(9);
  out << "{\"type\": \"triangles\", \"positions\": [";
  for (size_t i = 0; i < v.size(); ++i)
    out << (i ? "," : "") << "[" << v[i].x * radius << "," << v[i].y * radius << "," << v[i].z * radius << "]";
  out << "], \"indices\": [";
  for (size_t i = 0; i < f.size(); ++i) {
    auto tri = f[i];
    if (inward) std::swap(tri[1], tri[2]);
    out << (i ? "," : "") << "[" << tri[0] << "," << tri[1] << "," << tri[2] << "]";
  }
  out << "]";
  return out.str();  // the caller adds the material etc. and the closing brace
}

BinValues run_pdf_bins_kernel(ClKernel& k, cl_uint first, const SphereBinning& binning,
                              const std::vector<uint32_t>& bins, int order) {
  ClContext& cl = test_device();
  std::vector<double> nd, wd;
  gauss_legendre01(order, nd, wd);
  ClBuffer frame = upload(cl, binning.device_params()), b = upload(cl, bins),
           nodes = upload(cl, std::vector<float>(nd.begin(), nd.end())),
           weights = upload(cl, std::vector<float>(wd.begin(), wd.end()));
  ClBuffer out(cl, CL_MEM_WRITE_ONLY, bins.size() * 2 * sizeof(float));
  k.arg(first, frame.mem);
  k.arg(first + 1, b.mem);
  k.arg(first + 2, cl_uint(order));
  k.arg(first + 3, nodes.mem);
  k.arg(first + 4, weights.mem);
  k.arg(first + 5, out.mem);
  run_kernel(cl, k.k, bins.size());
  return bin_values(read_buffer<float>(cl, out, 2 * bins.size()));
}
