// A render is a pure function of scene, settings and seed: the same pixels on every run, for any
// work-group size, any split of the samples into passes and either BVH layout.
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

// The 4- and 8-wide BVHs (kernels/intersect.cl) give the same hits, ties included, so the same pixels:
// every bundled scene and every test scene that loads.
TEST(Determinism, BothBvhLayoutsGiveIdenticalPixels) {
  std::vector<std::string> files;
  for (std::string dir : {std::string(PATHCL_TEST_SCENES), std::string(PATHCL_TEST_SCENES) + "/../../scenes"})
    for (const auto& entry : std::filesystem::directory_iterator(dir))
      if (entry.path().extension() == ".json" && entry.path().filename().string().rfind("bad-", 0) != 0)
        files.push_back(entry.path().string());
  std::sort(files.begin(), files.end());
  ASSERT_GE(files.size(), 6u);
  for (const std::string& file : files) {
    DeviceScene scene = load_device_scene(file);
    scene.header.width = 32;
    scene.header.height = 24;
    std::vector<float> image[2];
    for (int i = 0; i < 2; ++i) {
      BvhWidthScope width(i ? 8 : 4);
      image[i] = render_with(scene, 5, 0, 0);
    }
    EXPECT_TRUE(bitwise_equal(image[0], image[1])) << file;
  }
}
