// Shared helpers of the device tests: the test device, temporary scene files, running pathcl.
#pragma once
#include <algorithm>
#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "runtime/device.h"
#include "runtime/kernel_program.h"
#include "runtime/renderer.h"
#include "runtime/scene_buffers.h"
#include "scene/device_scene_build.h"
#include "chi2.h"

// The device named by $PATHCL_TEST_DEVICE (default: pathcl's own default), one per test process.
ClContext& test_device();

// Sets PATHCL_BVH_WIDTH (runtime/device.h, bvh_width) for a scope: the BVH layout of every device.
struct BvhWidthScope {
  explicit BvhWidthScope(uint32_t width);
  ~BvhWidthScope();
  std::string saved;
  bool had = false;
};

// The test kernels of kernels/tests_sampling.cl, all features on, built once per process.
const KernelProgram& sampling_test_program();

// A device scene uploaded to the test device as the kernels take it (PC_SCENE_PARAMS of kernels/scene.cl).
inline SceneBuffers test_scene_buffers(const DeviceScene& scene) { return SceneBuffers(test_device(), scene, scene.header); }

// Reads n elements of a device buffer.
template <class T>
std::vector<T> read_buffer(ClContext& cl, const ClBuffer& buffer, size_t n) {
  std::vector<T> out(n);
  CL_CHECK(clEnqueueReadBuffer(cl.queue, buffer.mem, CL_TRUE, 0, n * sizeof(T), out.data(), 0, nullptr, nullptr));
  return out;
}

// A fresh temporary directory for this test, removed at exit.
std::string temp_dir();

// Writes text to a file in temp_dir() and returns its path.
std::string write_temp_file(const std::string& name, const std::string& text);

// Writes an 8-bit RGB PNG (rows from the top, 3 bytes per pixel) in temp_dir() and returns its path.
// rgb: 3 bytes a pixel, or 4 (RGBA).
std::string write_temp_png(const std::string& name, int width, int height, const std::vector<unsigned char>& rgb);

// Loads and flattens a scene file (around the camera, as `pathcl render` does, unless told otherwise;
// around the world origin with instances flattened, as `pathcl rays` does).
DeviceScene load_device_scene(const std::string& path, DeviceOrigin origin = DeviceOrigin::camera);

// The message of the SceneError that loading the scene file `path` throws, or "" if it loads.
std::string scene_load_error(const std::string& path);

// The whole file ("" if it cannot be read).
std::string read_text_file(const std::string& path);

// Runs the pathcl binary with arguments (shell words); returns the exit code, stderr in *err and
// stdout in *out when given.
int run_pathcl(const std::string& args, std::string* err = nullptr, std::string* out = nullptr);

// What the lane tests' kernels write (kernels/tests_sampling.cl, *_lanes_test): per work item, `stride`
// words of results at 16 lanes, then at 8 lanes, then at one lane. Counts the words where the 16- or
// 8-lane results differ from the one-lane ones, and in *valid the one-lane words that, read as floats,
// pass `valid`.
struct LaneComparison {
  size_t differing = 0, valid = 0;
};
LaneComparison compare_lanes(const std::vector<uint32_t>& bits, size_t items, size_t stride, bool (*valid)(float));
// Runs kernels/tests_sampling.cl's lane test `kernel` (PC_FLOAT_LANES_TEST_KERNEL) over `items` work items
// of 16 lanes reading `in`, with `stride` results per item and width (16 x its results per lane); returns
// the bits, as compare_lanes takes them.
std::vector<uint32_t> run_float_lanes_test(const char* kernel, const std::vector<float>& in, size_t items, size_t stride);

// Mean and standard error of the mean of values.
struct MeanStd {
  double mean = 0, std_error = 0;
};
MeanStd mean_and_error(const std::vector<double>& values);

// JSON text of a closed triangle mesh approximating a sphere (icosphere with `subdivisions`), CCW
// faces with normals pointing inwards when `inward` (for a camera inside).
std::string icosphere_json(float radius, int subdivisions, bool inward);

// |a - b| within tol relative to the larger magnitude.
inline bool close_rel(double a, double b, double tol) {
  return std::abs(a - b) <= tol * std::max({std::abs(a), std::abs(b), 1e-30});
}

// Runs one of kernels/tests_sampling.cl's *_pdf_bins kernels whose arguments before `first` are set:
// from `first` on it takes the binning, the bins, the Gauss-Legendre order, nodes and weights, and the
// output (integral, edge flag) per bin.
BinValues run_pdf_bins_kernel(ClKernel& k, cl_uint first, const SphereBinning& binning,
                              const std::vector<uint32_t>& bins, int order);
