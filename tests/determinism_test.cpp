// A render is a pure function of scene, settings and seed: the same pixels on every run, for any
// work-group size, any split of the samples into passes, either BVH layout and any lane width.
#include <cctype>
#include <cstdlib>
#include <cstring>
#include <filesystem>

#include <gtest/gtest.h>

#include "test_support.h"

namespace {

DeviceScene small_cornell() {
  DeviceScene scene = load_device_scene(std::string(PATHCL_TEST_SCENES) + "/../../scenes/cornell-box.json");
  scene.header.width = 48;
  scene.header.height = 40;
  return scene;
}

std::vector<float> render_with(const DeviceScene& scene, uint32_t seed, uint32_t pass_spp, size_t work_group) {
  RenderOptions opt;
  opt.spp = 12;
  opt.max_depth = 6;
  opt.seed = seed;
  opt.pass_spp = pass_spp;
  opt.work_group = work_group;
  return render(test_device(), scene, opt).film.mean;
}

bool bitwise_equal(const std::vector<float>& a, const std::vector<float>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0;
}

}  // namespace

TEST(Determinism, SameSeedGivesIdenticalPixels) {
  DeviceScene scene = small_cornell();
  std::vector<float> a = render_with(scene, 3, 0, 0), b = render_with(scene, 3, 0, 0);
  EXPECT_TRUE(bitwise_equal(a, b));
  std::vector<float> other = render_with(scene, 4, 0, 0);
  EXPECT_FALSE(bitwise_equal(a, other));  // the seed matters
}

TEST(Determinism, PassSplitDoesNotChangePixels) {
  DeviceScene scene = small_cornell();
  std::vector<float> reference = render_with(scene, 9, 12, 0);  // one pass
  for (uint32_t pass_spp : {0u, 1u, 5u, 7u}) EXPECT_TRUE(bitwise_equal(reference, render_with(scene, 9, pass_spp, 0))) << pass_spp;
}

TEST(Determinism, SplittingPixelsIntoUnitsDoesNotChangePixels) {
  DeviceScene scene = small_cornell();
  RenderOptions opt;
  opt.spp = 6;
  opt.max_depth = 6;
  opt.seed = 9;
  opt.pass_spp = 2;
  opt.tile_pixels = 1920;  // 48 x 40 pixels: one tile, a unit over the whole film
  RenderResult whole = render(test_device(), scene, opt);
  EXPECT_EQ(whole.launches, 3u);
  opt.tile_pixels = 111;
  opt.max_unit_pixels = 333;  // 6 units per pass, the last one short
  RenderResult split = render(test_device(), scene, opt);
  EXPECT_EQ(split.launches, 3u * 6u);
  EXPECT_TRUE(bitwise_equal(whole.film.mean, split.film.mean));
  EXPECT_EQ(whole.rays, split.rays);
}

TEST(Determinism, WorkGroupSizeDoesNotChangePixels) {
  DeviceScene scene = small_cornell();
  std::vector<float> reference = render_with(scene, 9, 4, 0);
  for (size_t wg : {size_t(16), size_t(64)}) EXPECT_TRUE(bitwise_equal(reference, render_with(scene, 9, 4, wg))) << wg;
}

// A launch's work group (runtime/device.h, launch_work_group): on a CPU device of 2 compute units, the lane
// kernels' 8 halved until the launch gives each unit 8 groups (the Cornell box at 96 x 72, 16 lanes: 27 items
// of 256 pixels, groups of 1), kept at 8 for 128 items or more; the tests' kernels' 64 the same way; kept
// where --work-group chose it and on GPUs, whose groups fill SIMD units. The pixels are the same bits
// (WorkGroupSizeDoesNotChangePixels compares the default's with chosen sizes').
TEST(Determinism, SmallLaunchesTakeSmallerWorkGroupsOnCpus) {
  DeviceInfo cpu;
  cpu.is_cpu = true;
  cpu.compute_units = 2;
  EXPECT_EQ(launch_work_group(cpu, 8, false, 27), 1u);
  EXPECT_EQ(launch_work_group(cpu, 8, false, 40), 2u);
  EXPECT_EQ(launch_work_group(cpu, 8, false, 64), 4u);
  EXPECT_EQ(launch_work_group(cpu, 8, false, 128), 8u);
  EXPECT_EQ(launch_work_group(cpu, 64, false, 6912), 64u);
  EXPECT_EQ(launch_work_group(cpu, 64, false, 100), 4u);
  EXPECT_EQ(launch_work_group(cpu, 8, true, 27), 8u);
  DeviceInfo gpu;
  gpu.is_gpu = true;
  gpu.compute_units = 132;
  EXPECT_EQ(launch_work_group(gpu, 64, false, 27), 64u);
}

// Every bundled scene and every test scene that loads.
std::vector<std::string> all_scene_files() {
  std::vector<std::string> files;
  for (std::string dir : {std::string(PATHCL_TEST_SCENES), std::string(PATHCL_TEST_SCENES) + "/../../scenes"})
    for (const auto& entry : std::filesystem::directory_iterator(dir))
      if (entry.path().extension() == ".json" && entry.path().filename().string().rfind("bad-", 0) != 0)
        files.push_back(entry.path().string());
  std::sort(files.begin(), files.end());
  return files;
}

TEST(Determinism, TheSceneTestsSeeEveryScene) { EXPECT_GE(all_scene_files().size(), 9u); }

// A test per scene file, named after it (CTest runs them in two shards at once: tests/CMakeLists.txt).
class EveryScene : public ::testing::TestWithParam<std::string> {};

std::string scene_test_name(const ::testing::TestParamInfo<std::string>& info) {
  std::string name = std::filesystem::path(info.param).stem().string();
  for (char& c : name)
    if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
  return name;
}

// The lane kernels (issue 15: 8 or 16 paths per work item, each lane starting its next sample when its path
// ends, the lanes' rays traced as packets on the 8- and 16-wide BVHs and one by one on the 4-wide one) and
// every BVH layout (kernels/intersect.cl: the same hits, ties included) give the film of one path per work item on
// the 4-wide BVH (the GPU path) bit for bit, accumulators and ray counts included, on a film whose pixel
// count is no multiple of the lanes, and with units and passes that split the lanes' pixels.
TEST_P(EveryScene, EveryLaneWidthAndBvhLayoutGiveIdenticalPixels) {
  const std::string& file = GetParam();
  DeviceScene scene = load_device_scene(file);
  scene.header.width = 31;
  scene.header.height = 23;
  RenderOptions opt;
  opt.spp = 12;
  opt.max_depth = 6;
  opt.seed = 5;
  opt.lanes = 1;
  RenderResult one;
  {
    BvhWidthScope layout(4);
    one = render(test_device(), scene, opt);
  }
  bool black = one.film.mean == std::vector<float>(one.film.mean.size(), 0.0f);
  EXPECT_EQ(black, std::filesystem::path(file).filename() == "empty.json") << "only empty.json renders black";
  for (uint32_t width : {4u, 8u, 16u}) {
    BvhWidthScope layout(width);
    for (uint32_t lanes : {1u, 8u, 16u}) {
      for (bool split : {false, true}) {
        if (lanes == 1 && width == 4 && !split) continue;  // the reference
        RenderOptions l = opt;
        l.lanes = lanes;
        if (split) l.tile_pixels = 37, l.max_unit_pixels = 111, l.pass_spp = 5;
        RenderResult r = render(test_device(), scene, l);
        std::string what = std::to_string(width) + "-wide BVH, " + std::to_string(lanes) + " lanes" + (split ? ", split" : "");
        EXPECT_EQ(r.film.words, one.film.words) << what;
        EXPECT_EQ(r.rays, one.rays) << what;
      }
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Determinism, EveryScene, ::testing::ValuesIn(all_scene_files()), scene_test_name);

TEST(Determinism, LanesOtherThanOneEightAndSixteenAreRefused) {
  RenderOptions opt;
  opt.spp = 1;
  opt.lanes = 4;
  EXPECT_THROW(render(test_device(), small_cornell(), opt), UsageError);
  opt.lanes = 8;
  opt.integrator = "mlt";
  EXPECT_THROW(render(test_device(), small_cornell(), opt), UsageError);
}

// The default (lanes 0) is each device's own width: 8 or 16 on a CPU device, 1 on a GPU; PATHCL_LANES sets
// it for every device and refuses other values, for path, light, bdpt and the merging integrators; the
// others run one path per work item.
TEST(Determinism, DefaultLanesAreTheDevicesOwn) {
  const char* outer = std::getenv("PATHCL_LANES");  // restored at the end
  std::string outer_lanes = outer ? outer : "";
  unsetenv("PATHCL_LANES");
  RenderOptions opt;
  opt.spp = 1;
  const DeviceInfo& device = test_device().info;
  RenderResult r = render(test_device(), small_cornell(), opt);
  ASSERT_FALSE(r.devices.empty());
  EXPECT_EQ(r.devices[0].lanes, path_lanes(device));
  EXPECT_EQ(r.devices[0].lanes, device.is_cpu ? (device.preferred_float_width >= 16 ? 16u : 8u) : 1u);
  // Devices that this machine may not have: CPUs whose preferred float vectors are 16 (AVX-512), 8 (AVX2)
  // and 4 (SSE) wide, and a GPU.
  DeviceInfo cpu = device;
  cpu.is_cpu = true, cpu.is_gpu = false;
  for (cl_uint width : {16u, 8u, 4u}) {
    cpu.preferred_float_width = width;
    EXPECT_EQ(path_lanes(cpu), width == 16 ? 16u : 8u) << width;
  }
  DeviceInfo gpu = cpu;
  gpu.is_cpu = false, gpu.is_gpu = true;
  EXPECT_EQ(path_lanes(gpu), 1u);
  setenv("PATHCL_LANES", "1", 1);
  EXPECT_EQ(render(test_device(), small_cornell(), opt).devices[0].lanes, 1u);
  setenv("PATHCL_LANES", "4", 1);
  EXPECT_THROW(render(test_device(), small_cornell(), opt), UsageError);
  unsetenv("PATHCL_LANES");
  for (const char* lanes : {"light", "bdpt", "vcm"}) {
    opt.integrator = lanes;
    EXPECT_EQ(render(test_device(), small_cornell(), opt).devices[0].lanes, path_lanes(device)) << lanes;
  }
  opt.integrator = "instant_radiosity";
  EXPECT_EQ(render(test_device(), small_cornell(), opt).devices[0].lanes, 1u);
  if (outer) setenv("PATHCL_LANES", outer_lanes.c_str(), 1);
}
