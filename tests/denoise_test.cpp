// Denoising with Intel Open Image Denoise (runtime/denoise.h, `pathcl denoise`): a noisy synthetic image
// gets much closer to the clean one, the same bits on every run, albedo and normal are used, and the
// command writes the denoised beauty, the raw layer and the attributes. The tests that run OIDN skip
// (and say why) only where the library is absent; the command's bad inputs and a missing library are
// tested everywhere.
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <random>
#include <string>

#include <gtest/gtest.h>

#include "runtime/denoise.h"
#include "runtime/errors.h"
#include "runtime/image_io.h"
#include "test_support.h"

namespace fs = std::filesystem;

namespace {

constexpr uint32_t W = 160, H = 120;

// A 2 x 2 grey beauty without layers: input for the command's error paths.
Image grey_2x2() {
  Image image;
  image.width = image.height = 2;
  image.rgb.assign(12, 0.5f);
  return image;
}

// A smooth image: horizontal and vertical gradients with a brighter disk (an edge to keep), in [0.1, 1.5].
std::vector<float> clean_image() {
  std::vector<float> rgb(size_t(W) * H * 3);
  for (uint32_t y = 0; y < H; ++y)
    for (uint32_t x = 0; x < W; ++x) {
      float u = float(x) / W, v = float(y) / H;
      bool disk = (u - 0.6f) * (u - 0.6f) + (v - 0.5f) * (v - 0.5f) < 0.04f;
      float* p = &rgb[(size_t(y) * W + x) * 3];
      p[0] = 0.1f + 0.6f * u + (disk ? 0.8f : 0.0f);
      p[1] = 0.1f + 0.5f * v + (disk ? 0.4f : 0.0f);
      p[2] = 0.3f + 0.2f * u * v;
    }
  return rgb;
}

// The clean image with Gaussian noise of sigma 0.15 (fixed seed), kept non-negative as a render's is.
std::vector<float> noisy(const std::vector<float>& clean) {
  std::mt19937 rng(12345);
  std::normal_distribution<float> noise(0.0f, 0.15f);
  std::vector<float> out(clean.size());
  for (size_t i = 0; i < clean.size(); ++i) out[i] = std::max(0.0f, clean[i] + noise(rng));
  return out;
}

double mse(const std::vector<float>& a, const std::vector<float>& b) {
  double s = 0;
  for (size_t i = 0; i < a.size(); ++i) s += (double(a[i]) - b[i]) * (double(a[i]) - b[i]);
  return s / double(a.size());
}

// The albedo (the clean image's colour without its gradient) and a normal facing the camera.
std::vector<float> albedo_image() {
  std::vector<float> albedo = clean_image();
  for (float& v : albedo) v = std::min(v, 1.0f);
  return albedo;
}
std::vector<float> normal_image() {
  std::vector<float> n(size_t(W) * H * 3, 0.0f);
  for (size_t p = 0; p < size_t(W) * H; ++p) n[3 * p + 2] = 1.0f;
  return n;
}

class Denoise : public testing::Test {
 protected:
  void SetUp() override {
    std::string why;
    if (denoiser_available(&why)) return;
    // scripts/test sets it: there (and in CI) the library is installed, and its absence is a failure.
    const char* required = std::getenv("PATHCL_REQUIRE_OIDN");
    if (required && *required && std::string(required) != "0") FAIL() << "PATHCL_REQUIRE_OIDN is set: " << why;
    GTEST_SKIP() << "Intel Open Image Denoise is not available: " << why;
  }
};

// An input EXR as a render with albedo and normal layers would write it, plus an id layer, variance and
// attributes to keep.
Image input_image() {
  Image image;
  image.width = W;
  image.height = H;
  image.rgb = noisy(clean_image());
  image.spp = 4;
  image.attributes = {{"renderer", "pathcl test"}, {"seed", "7"}, {"determinism", "bitwise"}};
  image.variance.assign(image.rgb.size(), 0.02f);
  image.layers.push_back({"albedo", {"R", "G", "B"}, albedo_image(), false});
  image.layers.push_back({"normal", {"X", "Y", "Z"}, normal_image(), false});
  std::vector<float> ids(size_t(W) * H);
  for (size_t i = 0; i < ids.size(); ++i) ids[i] = float(i % 5);
  image.layers.push_back({"object_id", {"id"}, ids, true});
  return image;
}

}  // namespace

TEST_F(Denoise, ReducesTheErrorOfANoisyImage) {
  std::vector<float> clean = clean_image(), input = noisy(clean);
  DenoiseResult r = denoise(W, H, input, nullptr, nullptr, DenoiseOptions{});
  ASSERT_EQ(r.rgb.size(), input.size());
  double before = mse(input, clean), after = mse(r.rgb, clean);
  EXPECT_GT(before / after, 4.0) << "MSE " << before << " -> " << after;
  EXPECT_FALSE(r.used_albedo);
  EXPECT_FALSE(r.used_normal);
  EXPECT_EQ(r.library_version.rfind("2.", 0), 0u) << r.library_version;
  EXPECT_EQ(r.device.rfind("CPU", 0), 0u) << r.device;
  EXPECT_GT(r.seconds, 0.0);
  for (const char* quality : {"balanced", "fast"}) {
    DenoiseOptions o;
    o.quality = quality;
    DenoiseResult q = denoise(W, H, input, nullptr, nullptr, o);
    EXPECT_GT(before / mse(q.rgb, clean), 4.0) << quality;
  }
}

TEST_F(Denoise, SameBitsOnEveryRun) {
  std::vector<float> input = noisy(clean_image()), albedo = albedo_image(), normal = normal_image();
  for (bool aux : {false, true}) {
    DenoiseResult a = denoise(W, H, input, aux ? &albedo : nullptr, aux ? &normal : nullptr, DenoiseOptions{});
    DenoiseResult b = denoise(W, H, input, aux ? &albedo : nullptr, aux ? &normal : nullptr, DenoiseOptions{});
    ASSERT_EQ(a.rgb.size(), b.rgb.size());
    EXPECT_EQ(std::memcmp(a.rgb.data(), b.rgb.data(), a.rgb.size() * sizeof(float)), 0) << "aux " << aux;
  }
}

TEST_F(Denoise, UsesAlbedoAndNormal) {
  std::vector<float> clean = clean_image(), input = noisy(clean), albedo = albedo_image(), normal = normal_image();
  std::vector<float> albedo_in = albedo, normal_in = normal;
  double before = mse(input, clean);
  DenoiseResult plain = denoise(W, H, input, nullptr, nullptr, DenoiseOptions{});
  for (bool clean_aux : {true, false}) {
    DenoiseOptions o;
    o.clean_aux = clean_aux;
    DenoiseResult r = denoise(W, H, input, &albedo, &normal, o);
    EXPECT_TRUE(r.used_albedo);
    EXPECT_TRUE(r.used_normal);
    EXPECT_GT(before / mse(r.rgb, clean), 4.0) << "clean_aux " << clean_aux;
    EXPECT_NE(r.rgb, plain.rgb) << "clean_aux " << clean_aux;  // the features changed the result
  }
  EXPECT_EQ(albedo, albedo_in);  // prefiltering works on copies
  EXPECT_EQ(normal, normal_in);
  DenoiseResult a = denoise(W, H, input, &albedo, nullptr, DenoiseOptions{});
  EXPECT_TRUE(a.used_albedo);
  EXPECT_FALSE(a.used_normal);
  DenoiseResult n = denoise(W, H, input, nullptr, &normal, DenoiseOptions{});  // OIDN needs an albedo beside it
  EXPECT_FALSE(n.used_normal);
  EXPECT_EQ(n.rgb, plain.rgb);
}

TEST_F(Denoise, BadArgumentsAreUsageErrors) {
  std::vector<float> input = noisy(clean_image()), small(10);
  DenoiseOptions o;
  o.quality = "best";
  EXPECT_THROW(denoise(W, H, input, nullptr, nullptr, o), UsageError);
  EXPECT_THROW(denoise(W, H, input, &small, nullptr, DenoiseOptions{}), UsageError);
  EXPECT_THROW(denoise(W, H + 1, input, nullptr, nullptr, DenoiseOptions{}), UsageError);
}

TEST_F(Denoise, DenoiseImageKeepsTheRawImageAndTheLayers) {
  Image image = input_image(), original = image;
  denoise_image(image, DenoiseOptions{});
  EXPECT_NE(image.rgb, original.rgb);
  const ImageLayer* raw = find_layer(image, "raw");
  ASSERT_NE(raw, nullptr);
  EXPECT_EQ(raw->channels, (std::vector<std::string>{"R", "G", "B"}));
  EXPECT_EQ(raw->values, original.rgb);
  EXPECT_EQ(image.layers.size(), original.layers.size() + 2);  // raw and raw.variance
  EXPECT_EQ(image.attributes.at("denoiser_aux"), "albedo,normal");
  EXPECT_EQ(image.attributes.at("denoiser_quality"), "high");
  EXPECT_EQ(image.attributes.at("denoiser").rfind("Intel Open Image Denoise 2.", 0), 0u);
  EXPECT_EQ(image.attributes.at("renderer"), "pathcl test");
}

// The render's determinism ("bitwise") describes the raw layer: it moves to raw.determinism, and the
// denoised beauty's is the denoiser's, the same bits only with the same library build on the same device
// and CPU, which the header names.
TEST_F(Denoise, DenoisedHeaderSaysWhatTheBitsDependOn) {
  Image image = input_image();
  denoise_image(image, DenoiseOptions{});
  EXPECT_EQ(image.attributes.at("determinism"), "denoiser-dependent");
  EXPECT_EQ(image.attributes.at("raw.determinism"), "bitwise");
  EXPECT_EQ(image.attributes.at("denoiser_device").rfind("CPU", 0), 0u) << image.attributes.at("denoiser_device");
  EXPECT_EQ(image.attributes.at("denoiser").rfind("Intel Open Image Denoise 2.", 0), 0u);
  EXPECT_EQ(image.attributes.at("denoiser_quality"), "high");
  Image again = image;  // denoised again: the render's value stays
  denoise_image(again, DenoiseOptions{});
  EXPECT_EQ(again.attributes.at("determinism"), "denoiser-dependent");
  EXPECT_EQ(again.attributes.at("raw.determinism"), "bitwise");
  Image foreign = input_image();  // a file without the attribute gets none for its raw layer
  foreign.attributes.erase("determinism");
  denoise_image(foreign, DenoiseOptions{});
  EXPECT_EQ(foreign.attributes.at("determinism"), "denoiser-dependent");
  EXPECT_EQ(foreign.attributes.count("raw.determinism"), 0u);
}

// A denoised image denoised again: the raw layer, the render, is the input, and it stays the render's; the
// result is that of denoising the render once with the new options, and with the same options the same
// image again.
TEST_F(Denoise, DenoisingADenoisedImageDenoisesItsRawLayerAndKeepsIt) {
  Image original = input_image(), image = original;
  denoise_image(image, DenoiseOptions{});
  Image twice = image;
  DenoiseOptions o;
  o.use_normal = false;
  denoise_image(twice, o);
  EXPECT_EQ(twice.layers.size(), image.layers.size());
  ASSERT_NE(find_layer(twice, "raw"), nullptr);
  EXPECT_EQ(find_layer(twice, "raw")->values, original.rgb);
  ASSERT_NE(find_layer(twice, "raw.variance"), nullptr);
  EXPECT_EQ(find_layer(twice, "raw.variance")->values, original.variance);
  EXPECT_EQ(twice.attributes.at("denoiser_aux"), "albedo");
  Image once = original;
  denoise_image(once, o);
  EXPECT_EQ(twice.rgb, once.rgb);
  Image again = image;
  denoise_image(again, DenoiseOptions{});
  EXPECT_EQ(again.rgb, image.rgb);
  EXPECT_EQ(find_layer(again, "raw")->values, original.rgb);

  // A file denoised by an older pathcl kept the raw beauty's variance at the top level: it moves to raw.variance.
  Image old = image;
  ASSERT_NE(find_layer(old, "raw.variance"), nullptr);
  old.variance = find_layer(old, "raw.variance")->values;
  old.layers.erase(std::find_if(old.layers.begin(), old.layers.end(), [](const ImageLayer& l) { return l.name == "raw.variance"; }));
  old.attributes["determinism"] = "bitwise";  // and its determinism, the render's, at the top level
  old.attributes.erase("raw.determinism");
  denoise_image(old, DenoiseOptions{});
  EXPECT_EQ(old.attributes.at("determinism"), "denoiser-dependent");
  EXPECT_EQ(old.attributes.at("raw.determinism"), "bitwise");
  EXPECT_TRUE(old.variance.empty());
  ASSERT_NE(find_layer(old, "raw.variance"), nullptr);
  EXPECT_EQ(find_layer(old, "raw.variance")->values, original.variance);
  EXPECT_EQ(old.rgb, image.rgb);

  // The command: the raw layer is the input, the summary says so, and the result is the first one's bits.
  std::string dir = temp_dir() + "/twice", in = dir + "/in.exr", once_path = dir + "/once.exr", twice_path = dir + "/twice.exr", err;
  fs::create_directories(dir);
  write_exr(in, original);
  ASSERT_EQ(run_pathcl("denoise " + in + " -o " + once_path, &err), 0) << err;
  ASSERT_EQ(run_pathcl("denoise " + once_path + " -o " + twice_path, &err), 0) << err;
  EXPECT_NE(err.find("its raw layer"), std::string::npos) << err;
  Image first = read_exr(once_path), second = read_exr(twice_path);
  ASSERT_NE(find_layer(second, "raw"), nullptr);
  EXPECT_EQ(find_layer(second, "raw")->values, original.rgb);
  EXPECT_EQ(second.rgb, first.rgb);
}

TEST_F(Denoise, CommandWritesTheDenoisedImageRawLayerAndAttributes) {
  std::string dir = temp_dir() + "/cli", in = dir + "/in.exr", out = dir + "/out/denoised.exr";
  fs::create_directories(dir);
  Image input = input_image();
  write_exr(in, input);
  std::string err;
  ASSERT_EQ(run_pathcl("denoise " + in + " -o " + out, &err), 0) << err;
  Image result = read_exr(out);
  double before = mse(input.rgb, clean_image()), after = mse(result.rgb, clean_image());
  EXPECT_GT(before / after, 4.0) << "MSE " << before << " -> " << after;
  const ImageLayer* raw = find_layer(result, "raw");
  ASSERT_NE(raw, nullptr);
  EXPECT_EQ(raw->values, input.rgb);
  for (const char* name : {"albedo", "normal", "object_id"}) {
    ASSERT_NE(find_layer(result, name), nullptr) << name;
    EXPECT_EQ(find_layer(result, name)->values, find_layer(input, name)->values) << name;
  }
  EXPECT_TRUE(find_layer(result, "object_id")->integer);
  EXPECT_TRUE(result.variance.empty());
  ASSERT_NE(find_layer(result, "raw.variance"), nullptr);
  EXPECT_EQ(find_layer(result, "raw.variance")->values, input.variance);
  EXPECT_EQ(result.spp, 4);
  EXPECT_EQ(result.attributes.at("renderer"), "pathcl test");
  EXPECT_EQ(result.attributes.at("seed"), "7");
  EXPECT_EQ(result.attributes.at("denoiser").rfind("Intel Open Image Denoise 2.", 0), 0u);
  EXPECT_EQ(result.attributes.at("denoiser_quality"), "high");
  EXPECT_EQ(result.attributes.at("denoiser_aux"), "albedo,normal");
  EXPECT_NE(err.find("denoised 160x120"), std::string::npos) << err;

  // The same bits as the library call.
  Image direct = input;
  denoise_image(direct, DenoiseOptions{});
  EXPECT_EQ(result.rgb, direct.rgb);

  ASSERT_EQ(run_pathcl("denoise " + in + " -o " + out + " --no-aux --quality fast -q", &err), 0) << err;
  EXPECT_EQ(err, "");
  result = read_exr(out);
  EXPECT_EQ(result.attributes.at("denoiser_aux"), "none");
  EXPECT_EQ(result.attributes.at("denoiser_quality"), "fast");
}

// Fewer guides when asked for: --aux albedo uses the albedo alone, --no-aux none; denoise_image refuses a
// guide it is asked for and the image lacks, and leaves the image as it was.
TEST_F(Denoise, FewerGuidesOnlyWhenAskedFor) {
  Image image = input_image();
  image.layers.erase(image.layers.begin() + 1);  // the normal
  ASSERT_EQ(find_layer(image, "normal"), nullptr);
  Image unchanged = image;
  EXPECT_THROW(denoise_image(image, DenoiseOptions{}), UsageError);
  EXPECT_EQ(image.rgb, unchanged.rgb);
  EXPECT_EQ(image.layers.size(), unchanged.layers.size());
  EXPECT_EQ(image.attributes, unchanged.attributes);
  DenoiseOptions normal_alone;
  normal_alone.use_albedo = false;
  EXPECT_THROW(denoise_image(image, normal_alone), UsageError);

  std::string dir = temp_dir() + "/fewer", in = dir + "/in.exr", out = dir + "/out.exr", err;
  fs::create_directories(dir);
  write_exr(in, image);
  ASSERT_EQ(run_pathcl("denoise " + in + " -o " + out + " --aux albedo -q", &err), 0) << err;
  EXPECT_EQ(read_exr(out).attributes.at("denoiser_aux"), "albedo");
  ASSERT_EQ(run_pathcl("denoise " + in + " -o " + out + " --aux none -q", &err), 0) << err;
  EXPECT_EQ(read_exr(out).attributes.at("denoiser_aux"), "none");
}

// The variance describes the raw beauty: it goes with it, into the layer raw.variance, and the denoised
// image has none, so that `pathcl compare` does not z-test the denoised beauty against the raw one's noise.
TEST_F(Denoise, VarianceGoesWithTheRawBeauty) {
  Image image = input_image(), original = image;
  denoise_image(image, DenoiseOptions{});
  EXPECT_TRUE(image.variance.empty());
  const ImageLayer* variance = find_layer(image, "raw.variance");
  ASSERT_NE(variance, nullptr);
  EXPECT_EQ(variance->channels, (std::vector<std::string>{"R", "G", "B"}));
  EXPECT_EQ(variance->values, original.variance);
  EXPECT_FALSE(variance->integer);

  // In the files: channels raw.variance.R/G/B, no variance.R/G/B; compare finds no variance to z-test.
  std::string dir = temp_dir() + "/variance", in = dir + "/in.exr", out = dir + "/denoised.exr", err, text;
  fs::create_directories(dir);
  write_exr(in, original);
  ASSERT_EQ(run_pathcl("denoise " + in + " -o " + out + " -q", &err), 0) << err;
  Image result = read_exr(out);
  EXPECT_TRUE(result.variance.empty());
  ASSERT_NE(find_layer(result, "raw.variance"), nullptr);
  EXPECT_EQ(find_layer(result, "raw.variance")->values, original.variance);
  ASSERT_EQ(run_pathcl("compare " + in + " " + out, &err, &text), 0) << err;
  EXPECT_NE(text.find("z_test none"), std::string::npos) << text;
}

// These need no library: bad input is found before denoising, and the search obeys PATHCL_OIDN_LIBRARY.
TEST(DenoiseCommand, BadInputExitsWith2) {
  std::string dir = temp_dir() + "/bad-input";
  fs::create_directories(dir);
  std::string out = dir + "/out.exr", err;
  EXPECT_EQ(run_pathcl("denoise " + dir + "/missing.exr -o " + out, &err), 2);
  EXPECT_NE(err.find(dir + "/missing.exr"), std::string::npos) << err;
  std::string text = write_temp_file("bad-input/text.exr", "not an EXR file\n");
  EXPECT_EQ(run_pathcl("denoise " + text + " -o " + out, &err), 2);
  EXPECT_NE(err.find(text), std::string::npos) << err;
  Image image = grey_2x2();
  std::string good = dir + "/good.exr";
  write_exr(good, image);
  EXPECT_EQ(run_pathcl("denoise " + good + " -o " + out + " --quality best", &err), 2);
  EXPECT_NE(err.find("--quality best"), std::string::npos) << err;
  EXPECT_EQ(run_pathcl("denoise " + good + " -o " + dir, &err), 2);  // a directory
  EXPECT_EQ(run_pathcl("denoise " + good + " -o " + dir + "/out.txt", &err), 2);
  EXPECT_EQ(run_pathcl("denoise " + good, &err), 2);  // -o is required
  EXPECT_FALSE(fs::exists(out));
}

// A layer "raw" that is not the R, G, B of a beauty cannot be denoised again: exit 2, naming the file
// and what was expected; nothing written.
TEST(DenoiseCommand, RawLayerThatIsNotRgbExitsWith2) {
  std::string dir = temp_dir() + "/bad-raw";
  fs::create_directories(dir);
  Image image = grey_2x2();
  image.layers.push_back({"raw", {"R", "G"}, std::vector<float>(8, 0.5f), false});
  std::string in = dir + "/in.exr", out = dir + "/out.exr", err;
  write_exr(in, image);
  EXPECT_EQ(run_pathcl("denoise " + in + " -o " + out + " --no-aux", &err), 2) << err;
  EXPECT_NE(err.find(in + ": the layer \"raw\" has the channels raw.R, raw.G"), std::string::npos) << err;
  EXPECT_NE(err.find("expected the float channels raw.R, raw.G, raw.B"), std::string::npos) << err;
  EXPECT_FALSE(fs::exists(out));
}

// A guide that the command asks for (albedo and normal unless --aux or --no-aux says fewer) and the file
// lacks is an error, not a quiet fall-back to fewer guides: exit 2, naming the file, the layers or channels
// missing and the options that ask for fewer; nothing written.
TEST(DenoiseCommand, MissingGuidesExitWith2) {
  std::string dir = temp_dir() + "/no-guides", out = dir + "/out.exr", err;
  fs::create_directories(dir);
  Image image = grey_2x2();
  std::string none = dir + "/none.exr";
  write_exr(none, image);
  EXPECT_EQ(run_pathcl("denoise " + none + " -o " + out, &err), 2) << err;
  EXPECT_NE(err.find(none + ": no layer albedo (albedo.R, albedo.G, albedo.B) and no layer normal (normal.X, normal.Y, "
                            "normal.Z) to guide the denoiser"), std::string::npos) << err;
  EXPECT_NE(err.find("--aov albedo,normal"), std::string::npos) << err;
  EXPECT_NE(err.find("--no-aux (the colour alone)"), std::string::npos) << err;
  EXPECT_EQ(err.find("--aux albedo"), std::string::npos) << err;  // there is no albedo to use alone
  EXPECT_EQ(run_pathcl("denoise " + none + " -o " + out + " --aux albedo", &err), 2) << err;
  EXPECT_NE(err.find(none + ": no layer albedo (albedo.R, albedo.G, albedo.B) to guide"), std::string::npos) << err;

  image.layers.push_back({"albedo", {"R", "G", "B"}, std::vector<float>(12, 0.5f), false});
  std::string albedo = dir + "/albedo.exr";
  write_exr(albedo, image);
  EXPECT_EQ(run_pathcl("denoise " + albedo + " -o " + out, &err), 2) << err;
  EXPECT_NE(err.find(albedo + ": no layer normal (normal.X, normal.Y, normal.Z) to guide"), std::string::npos) << err;
  EXPECT_NE(err.find("--aux albedo (the albedo alone) or --no-aux"), std::string::npos) << err;

  image.layers.push_back({"normal", {"X", "Y"}, std::vector<float>(8, 0.0f), false});
  std::string partial = dir + "/partial.exr";
  write_exr(partial, image);
  EXPECT_EQ(run_pathcl("denoise " + partial + " -o " + out, &err), 2) << err;
  EXPECT_NE(err.find(partial + ": no normal.Z in the layer normal (normal.X, normal.Y, normal.Z)"), std::string::npos) << err;

  EXPECT_EQ(run_pathcl("denoise " + albedo + " -o " + out + " --aux normal", &err), 2) << err;
  EXPECT_NE(err.find("--aux normal: expected albedo,normal, albedo or none"), std::string::npos) << err;
  EXPECT_EQ(run_pathcl("denoise " + albedo + " -o " + out + " --aux albedo --no-aux", &err), 2) << err;
  EXPECT_FALSE(fs::exists(out));
}

TEST(DenoiseCommand, MissingLibraryExitsWith1AndSaysHowToGetIt) {
  std::string dir = temp_dir() + "/no-library";
  fs::create_directories(dir);
  Image image = grey_2x2();
  std::string in = dir + "/in.exr", out = dir + "/out.exr", err;
  write_exr(in, image);
  std::string saved = std::getenv("PATHCL_OIDN_LIBRARY") ? std::getenv("PATHCL_OIDN_LIBRARY") : "";
  setenv("PATHCL_OIDN_LIBRARY", "/nonexistent/libOpenImageDenoise.so.2", 1);
  int code = run_pathcl("denoise " + in + " -o " + out + " --no-aux", &err);
  if (saved.empty())
    unsetenv("PATHCL_OIDN_LIBRARY");
  else
    setenv("PATHCL_OIDN_LIBRARY", saved.c_str(), 1);
  EXPECT_EQ(code, 1) << err;
  EXPECT_NE(err.find("Intel Open Image Denoise 2.x"), std::string::npos) << err;
  EXPECT_NE(err.find("scripts/setup"), std::string::npos) << err;
  EXPECT_NE(err.find("PATHCL_OIDN_LIBRARY"), std::string::npos) << err;
  EXPECT_NE(err.find("/nonexistent/libOpenImageDenoise.so.2"), std::string::npos) << err;
  EXPECT_FALSE(fs::exists(out));
}

// `pathcl render --denoise`: the raw beauty kept as the layer raw is the bits of a render without it, and
// with --variance its variance goes beside it (raw.variance), not to the top level; the albedo and normal
// AOVs are rendered for the denoiser, and the header names it.
TEST_F(Denoise, RenderDenoiseKeepsTheRawBeautyAndNamesTheDenoiser) {
  std::string scene = std::string(PATHCL_TEST_SCENES) + "/tiny.json", dir = temp_dir(), err;
  ASSERT_EQ(run_pathcl("render " + scene + " --spp 4 -q --variance --denoise -o " + dir + "/denoised.exr", &err), 0) << err;
  ASSERT_EQ(run_pathcl("render " + scene + " --spp 4 -q --variance -o " + dir + "/plain.exr", &err), 0) << err;
  Image denoised = read_exr(dir + "/denoised.exr"), plain = read_exr(dir + "/plain.exr");
  const ImageLayer* raw = find_layer(denoised, "raw");
  ASSERT_NE(raw, nullptr);
  EXPECT_EQ(raw->values, plain.rgb);
  EXPECT_TRUE(denoised.variance.empty());
  ASSERT_NE(find_layer(denoised, "raw.variance"), nullptr);
  EXPECT_EQ(find_layer(denoised, "raw.variance")->values, plain.variance);
  EXPECT_NE(denoised.rgb, plain.rgb);
  EXPECT_NE(find_layer(denoised, "albedo"), nullptr);
  EXPECT_NE(find_layer(denoised, "normal"), nullptr);
  EXPECT_EQ(denoised.attributes["denoiser_aux"], "albedo,normal");
  EXPECT_EQ(denoised.attributes["denoiser"].rfind("Intel Open Image Denoise 2.", 0), 0u) << denoised.attributes["denoiser"];
  EXPECT_EQ(denoised.attributes["denoiser_device"].rfind("CPU", 0), 0u) << denoised.attributes["denoiser_device"];
  EXPECT_EQ(plain.attributes["determinism"], "bitwise");
  EXPECT_EQ(denoised.attributes["raw.determinism"], "bitwise");
  EXPECT_EQ(denoised.attributes["determinism"], "denoiser-dependent");
}
