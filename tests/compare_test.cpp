// Image comparison: metrics on images with known answers, masks, the per-pixel z-test, the EXR
// variance channels, and `pathcl compare`.
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "runtime/errors.h"
#include "runtime/image_compare.h"
#include "runtime/image_io.h"
#include "test_support.h"

namespace {

// float inputs: 1.1f - 1.0f is 0.1 only to about 1e-7.
constexpr double kTol = 1e-6;

Image filled(uint32_t width, uint32_t height, float r, float g, float b) {
  Image image;
  image.width = width;
  image.height = height;
  for (size_t p = 0; p < size_t(width) * height; ++p) image.rgb.insert(image.rgb.end(), {r, g, b});
  return image;
}

void set_pixel(std::vector<float>& buffer, uint32_t width, uint32_t x, uint32_t y, float r, float g, float b) {
  size_t i = (size_t(y) * width + x) * 3;
  buffer[i] = r;
  buffer[i + 1] = g;
  buffer[i + 2] = b;
}


}  // namespace

TEST(Compare, UniformOffset) {
  Image reference = filled(4, 2, 1, 1, 1), test = filled(4, 2, 1.1f, 1.1f, 1.1f);
  ImageErrors e = compare_images(reference, test, nullptr);
  EXPECT_EQ(e.pixels, 8u);
  EXPECT_NEAR(e.rmse, 0.1, kTol);
  EXPECT_NEAR(e.mae, 0.1, kTol);
  EXPECT_NEAR(e.rel_mse, 0.01 / 1.01, kTol);
  for (int c = 0; c < 3; ++c) {
    EXPECT_NEAR(e.bias[c], 0.1, kTol);
    EXPECT_NEAR(e.mean_reference[c], 1.0, kTol);
    EXPECT_NEAR(e.mean_test[c], 1.1, kTol);
  }
  EXPECT_FALSE(e.has_z_test);
  EXPECT_EQ(e.z_threshold, 3.29);

  ImageErrors same = compare_images(reference, reference, nullptr);
  EXPECT_EQ(same.rmse, 0);
  EXPECT_EQ(same.rel_mse, 0);
  EXPECT_EQ(same.mae, 0);
}

TEST(Compare, MaskSelectsPixelsByItsRedChannel) {
  // Reference 0. Left half (x < 2): a huge error, masked out. Right half: d = (0.5, -0.25, 0).
  Image reference = filled(4, 2, 0, 0, 0), test = filled(4, 2, 0.5f, -0.25f, 0);
  Image mask = filled(4, 2, 0, 1, 1);  // only R counts, so G and B of 1 must not select pixels
  for (uint32_t y = 0; y < 2; ++y)
    for (uint32_t x = 0; x < 2; ++x) set_pixel(test.rgb, 4, x, y, 100, 100, 100);
  for (uint32_t y = 0; y < 2; ++y)
    for (uint32_t x = 2; x < 4; ++x) set_pixel(mask.rgb, 4, x, y, 1, 0, 0);
  ImageErrors e = compare_images(reference, test, &mask);
  EXPECT_EQ(e.pixels, 4u);
  double mse = (0.25 + 0.0625 + 0) / 3;
  EXPECT_NEAR(e.rmse, std::sqrt(mse), kTol);
  EXPECT_NEAR(e.rel_mse, mse / 0.01, kTol);  // reference 0: divided by 0 + 0.01
  EXPECT_NEAR(e.mae, 0.75 / 3, kTol);
  EXPECT_NEAR(e.bias[0], 0.5, kTol);
  EXPECT_NEAR(e.bias[1], -0.25, kTol);
  EXPECT_NEAR(e.bias[2], 0, kTol);
  EXPECT_NEAR(e.mean_test[0], 0.5, kTol);

  Image nothing = filled(4, 2, 0, 1, 1);
  EXPECT_THROW(compare_images(reference, test, &nothing), UsageError);
}

TEST(Compare, ZTestCountsPixelsBeyondTheThreshold) {
  // 10 pixels, reference 0, standard deviation 0.1 everywhere. 3 pixels have |z| = 10 in G only; one
  // has |z| = 3 (under 3.29); the rest |z| = 1.
  const uint32_t n = 10;
  Image reference = filled(n, 1, 0, 0, 0), test = filled(n, 1, 0.1f, -0.1f, 0.1f);
  test.variance.assign(n * 3, 0.01f);
  for (uint32_t x : {1u, 4u, 8u}) set_pixel(test.rgb, n, x, 0, 0.1f, 1.0f, 0.1f);
  set_pixel(test.rgb, n, 6, 0, -0.3f, 0.1f, 0.1f);
  ImageErrors e = compare_images(reference, test, nullptr);
  EXPECT_TRUE(e.has_z_test);
  EXPECT_NEAR(e.z_fail_fraction, 3.0 / n, 1e-12);

  // A lower threshold: the |z| = 3 pixel fails as well; at 0.5 every pixel does.
  EXPECT_NEAR(compare_images(reference, test, nullptr, 2.5).z_fail_fraction, 4.0 / n, 1e-12);
  EXPECT_NEAR(compare_images(reference, test, nullptr, 0.5).z_fail_fraction, 1.0, 1e-12);
  EXPECT_EQ(compare_images(reference, test, nullptr, 0.5).z_threshold, 0.5);

  // With a mask over pixels 0 to 4: 2 of the 5 fail (pixels 1 and 4).
  Image mask = filled(n, 1, 0, 0, 0);
  for (uint32_t x = 0; x < 5; ++x) set_pixel(mask.rgb, n, x, 0, 1, 0, 0);
  EXPECT_NEAR(compare_images(reference, test, &mask).z_fail_fraction, 2.0 / 5, 1e-12);
}

TEST(Compare, ZeroVarianceFailsOnlyOnADifference) {
  Image reference = filled(4, 1, 0.5f, 0.5f, 0.5f), test = reference;
  test.variance.assign(4 * 3, 0.0f);
  set_pixel(test.rgb, 4, 2, 0, 0.5f, 0.5f, 0.5001f);  // a tiny difference with claimed zero variance
  ImageErrors e = compare_images(reference, test, nullptr);
  EXPECT_TRUE(e.has_z_test);
  EXPECT_NEAR(e.z_fail_fraction, 0.25, 1e-12);
}

TEST(Compare, BadInputIsAUsageError) {
  Image a = filled(4, 2, 1, 1, 1), b = filled(2, 2, 1, 1, 1);
  try {
    compare_images(a, b, nullptr);
    FAIL() << "no error";
  } catch (const UsageError& e) {
    EXPECT_STREQ(e.what(), "image sizes differ: 4x2 vs 2x2");
  }
  EXPECT_THROW(compare_images(a, a, &b), UsageError);

  Image nan = a;
  nan.rgb[0] = NAN;
  nan.rgb[5] = INFINITY;
  try {
    compare_images(a, nan, nullptr);
    FAIL() << "no error";
  } catch (const UsageError& e) {
    EXPECT_NE(std::string(e.what()).find("2 in the test image"), std::string::npos) << e.what();
  }
  // A non-finite value the mask leaves out does not matter.
  Image mask = filled(4, 2, 1, 1, 1);
  set_pixel(mask.rgb, 4, 0, 0, 0, 0, 0);
  set_pixel(mask.rgb, 4, 1, 0, 0, 0, 0);
  EXPECT_NO_THROW(compare_images(a, nan, &mask));

  Image negative_variance = a;
  negative_variance.variance.assign(4 * 2 * 3, -1.0f);
  EXPECT_THROW(compare_images(a, negative_variance, nullptr), UsageError);
}

TEST(Compare, ExrRoundTripsTheVarianceChannels) {
  Image image = filled(3, 2, 0.25f, 0.5f, 0.75f);
  image.variance.resize(3 * 2 * 3);
  for (size_t i = 0; i < image.variance.size(); ++i) image.variance[i] = 0.001f * float(i + 1);
  image.spp = 7;
  std::string path = temp_dir() + "/variance.exr";
  write_exr(path, image);
  EXPECT_FALSE(std::filesystem::exists(path + ".partial.exr"));
  Image back = read_exr(path);
  EXPECT_EQ(back.width, 3u);
  EXPECT_EQ(back.height, 2u);
  EXPECT_EQ(back.spp, 7);
  EXPECT_EQ(back.rgb, image.rgb);
  EXPECT_EQ(back.variance, image.variance);

  // Without variance the file has none and reads back none.
  image.variance.clear();
  write_exr(path, image);
  back = read_exr(path);
  EXPECT_EQ(back.rgb, image.rgb);
  EXPECT_TRUE(back.variance.empty());
}

TEST(Compare, ReadExrRejectsFilesWithoutRgb) {
  // Write an RGB file and rename its channel R to S in the (uncompressed) header: an EXR with
  // channels B, G, S, which OpenEXR reads fine but which is not an RGB image.
  std::string path = temp_dir() + "/no-red.exr";
  write_exr(path, filled(2, 2, 1, 1, 1));
  std::string bytes;
  {
    std::stringstream ss;
    ss << std::ifstream(path, std::ios::binary).rdbuf();
    bytes = ss.str();
  }
  size_t list = bytes.find(std::string("chlist\0", 7));
  ASSERT_NE(list, std::string::npos);
  size_t red = bytes.find(std::string("\0R\0", 3), list);
  ASSERT_NE(red, std::string::npos);
  bytes[red + 1] = 'S';
  std::ofstream(path, std::ios::binary) << bytes;
  try {
    read_exr(path);
    FAIL() << "no error";
  } catch (const UsageError& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("R, G and B"), std::string::npos) << e.what();
  }
}

TEST(Compare, CommandLine) {
  std::string dir = temp_dir();
  Image reference = filled(4, 2, 1, 1, 1), test = filled(4, 2, 1.1f, 1.1f, 1.1f);
  test.variance.assign(4 * 2 * 3, 0.01f);                // |z| = 1: passes
  set_pixel(test.variance, 4, 3, 1, 0.01f, 1e-4f, 0.01f);  // |z| = 10 in G: fails
  write_exr(dir + "/ref.exr", reference);
  write_exr(dir + "/test.exr", test);
  ImageErrors expected = compare_images(reference, test, nullptr);

  std::string out, err;
  ASSERT_EQ(run_pathcl("compare " + dir + "/ref.exr " + dir + "/test.exr --json", &err, &out), 0) << err;
  nlohmann::json j = nlohmann::json::parse(out);
  EXPECT_EQ(j["pixels"], 8);
  EXPECT_NEAR(j["rmse"].get<double>(), 0.1, kTol);
  EXPECT_NEAR(j["relmse"].get<double>(), 0.01 / 1.01, kTol);
  EXPECT_NEAR(j["mae"].get<double>(), 0.1, kTol);
  EXPECT_DOUBLE_EQ(j["rmse"].get<double>(), expected.rmse);
  EXPECT_DOUBLE_EQ(j["relmse"].get<double>(), expected.rel_mse);
  for (int c = 0; c < 3; ++c) {
    EXPECT_NEAR(j["bias"][c].get<double>(), 0.1, kTol);
    EXPECT_NEAR(j["mean_reference"][c].get<double>(), 1.0, kTol);
    EXPECT_NEAR(j["mean_test"][c].get<double>(), 1.1, kTol);
  }
  EXPECT_EQ(j["z_test"], true);
  EXPECT_DOUBLE_EQ(j["z_fail_fraction"].get<double>(), 1.0 / 8);
  EXPECT_DOUBLE_EQ(j["z_threshold"].get<double>(), 3.29);

  // The reference against itself: no variance channel, so no z-test; text output.
  ASSERT_EQ(run_pathcl("compare " + dir + "/test.exr " + dir + "/ref.exr --json --z-threshold 2", &err, &out), 0)
      << err;
  j = nlohmann::json::parse(out);
  EXPECT_EQ(j["z_test"], false);
  EXPECT_TRUE(j["z_fail_fraction"].is_null());
  EXPECT_DOUBLE_EQ(j["z_threshold"].get<double>(), 2.0);
  ASSERT_EQ(run_pathcl("compare " + dir + "/ref.exr " + dir + "/test.exr", &err, &out), 0) << err;
  EXPECT_NE(out.find("\nrmse 0.1"), std::string::npos) << out;
  EXPECT_NE(out.find("\nz_fail_fraction 0.125"), std::string::npos) << out;

  // A mask on the right half leaves 4 pixels, 1 of them failing.
  Image mask = filled(4, 2, 0, 0, 0);
  for (uint32_t y = 0; y < 2; ++y)
    for (uint32_t x = 2; x < 4; ++x) set_pixel(mask.rgb, 4, x, y, 1, 1, 1);
  write_exr(dir + "/mask.exr", mask);
  ASSERT_EQ(run_pathcl("compare " + dir + "/ref.exr " + dir + "/test.exr --json --mask " + dir + "/mask.exr", &err, &out),
            0) << err;
  j = nlohmann::json::parse(out);
  EXPECT_EQ(j["pixels"], 4);
  EXPECT_DOUBLE_EQ(j["z_fail_fraction"].get<double>(), 0.25);

  // Bad input exits with 2 and names the files.
  write_exr(dir + "/small.exr", filled(2, 2, 1, 1, 1));
  EXPECT_EQ(run_pathcl("compare " + dir + "/ref.exr " + dir + "/small.exr", &err), 2);
  EXPECT_NE(err.find("small.exr"), std::string::npos) << err;
  EXPECT_NE(err.find("image sizes differ: 4x2 vs 2x2"), std::string::npos) << err;
  EXPECT_EQ(run_pathcl("compare " + dir + "/ref.exr " + dir + "/test.exr --mask " + dir + "/small.exr", &err), 2);
  EXPECT_NE(err.find("small.exr"), std::string::npos) << err;
  EXPECT_EQ(run_pathcl("compare " + dir + "/ref.exr " + dir + "/missing.exr --json", &err), 2);
  EXPECT_NE(err.find("missing.exr"), std::string::npos) << err;
  std::ofstream(dir + "/garbage.exr") << "not an EXR file";
  EXPECT_EQ(run_pathcl("compare " + dir + "/garbage.exr " + dir + "/ref.exr", &err), 2);
  EXPECT_NE(err.find("garbage.exr: cannot read the EXR file"), std::string::npos) << err;
  EXPECT_EQ(run_pathcl("compare " + dir + "/ref.exr"), 2);
  EXPECT_EQ(run_pathcl("compare " + dir + "/ref.exr " + dir + "/test.exr --z-threshold 0"), 2);
}
