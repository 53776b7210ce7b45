// Cut-outs (kernels/cutout.cl): a material's opacity is the probability that its surface stops a ray,
// camera, scattered and shadow rays alike, so what passes is exactly 1 - opacity in expectation; opacity
// maps read grey maps (red) and alpha channels linearly; the decision is the same in both BVH layouts.
#include <cmath>
#include <cstring>
#include <string>

#include <gtest/gtest.h>

#include "scene/scene_error.h"
#include "test_support.h"

namespace {

RenderResult render_scene(const DeviceScene& scene, uint32_t spp, uint32_t max_depth) {
  RenderOptions opt;
  opt.spp = spp;
  opt.max_depth = max_depth;
  opt.seed = 5;
  opt.sampler = PC_SAMPLER_INDEPENDENT;  // the film's variances are exact for it
  RenderResult r = render(test_device(), scene, opt);
  EXPECT_EQ(r.nan_samples + r.inf_samples + r.negative_samples, 0u);
  return r;
}

// Every pixel's red channel against `expected`, within 4 standard errors per pixel (its own sample
// variance) and for the image mean.
void expect_red_everywhere(const Film& film, double expected, const std::string& what) {
  std::vector<double> means;
  int failures = 0;
  for (size_t i = 0; i < film.mean.size(); i += 3) {
    double error = std::sqrt(film.variance[i]);
    if (std::abs(film.mean[i] - expected) > 4 * error + 1e-7 && ++failures < 5)
      ADD_FAILURE() << what << ": pixel " << i / 3 << ": " << film.mean[i] << " +- " << error << ", expected " << expected;
    means.push_back(film.mean[i]);
  }
  MeanStd m = mean_and_error(means);
  EXPECT_NEAR(m.mean, expected, 4 * m.std_error + 1e-7) << what;
  EXPECT_LT(m.std_error, 0.01) << what;  // the test can tell opacities 0.04 apart
}

// A black quad filling the camera's view in front of a white sky; `opacity` is its material's.
std::string quad_in_front_of_the_sky(const std::string& opacity) {
  return R"({"camera": {"position": [0, 0, 2], "look_at": [0, 0, 0], "fov_y_degrees": 30, "width": 12, "height": 12},
    "materials": {"black": {"type": "diffuse", "reflectance": [0, 0, 0], "opacity": )" + opacity + R"(}},
    "shapes": [{"type": "triangles", "material": "black", "positions": [[-3, -3, 0], [3, -3, 0], [3, 3, 0], [-3, 3, 0]],
                "uvs": [[0, 0], [1, 0], [1, 1], [0, 1]], "indices": [[0, 1, 2], [0, 2, 3]]}],
    "lights": [{"type": "environment", "radiance": [1, 1, 1]}]})";
}

}  // namespace

// Camera rays: a sample is 1 (the sky, through the quad) or 0 (the black quad).
TEST(Cutout, AQuadOfOpacityALetsOneMinusAOfTheSkyThrough) {
  for (double opacity : {0.0, 0.3, 0.75, 1.0}) {
    DeviceScene scene = load_device_scene(write_temp_file("cutout-quad.json", quad_in_front_of_the_sky(std::to_string(opacity))));
    EXPECT_EQ(bool(scene.features & kFeatureCutouts), opacity < 1);
    expect_red_everywhere(render_scene(scene, 256, 2).film, 1 - opacity, "opacity " + std::to_string(opacity));
  }
}

// Opacity maps: a grey PNG is read from its red channel, an RGBA PNG from its alpha, both linearly (a
// byte b is b / 255, not an sRGB value).
TEST(Cutout, OpacityMapsReadTheRedOrTheAlphaChannelLinearly) {
  write_temp_png("cutout/grey.png", 2, 2, std::vector<unsigned char>(12, 64));
  std::vector<unsigned char> rgba;
  for (int i = 0; i < 4; ++i) rgba.insert(rgba.end(), {255, 255, 255, 191});
  write_temp_png("cutout/alpha.png", 2, 2, rgba);
  for (auto [file, opacity] : {std::pair<std::string, double>{"cutout/grey.png", 64 / 255.0},
                               std::pair<std::string, double>{"cutout/alpha.png", 191 / 255.0}}) {
    DeviceScene scene = load_device_scene(
        write_temp_file("cutout-map.json", quad_in_front_of_the_sky(R"({"texture": ")" + file + R"("})")));
    EXPECT_TRUE(scene.features & kFeatureCutouts);
    expect_red_everywhere(render_scene(scene, 256, 2).film, 1 - opacity, file);
  }
}

// Shadow rays: a directional light straight down on a diffuse floor of albedo rho, through a black
// cut-out sheet of opacity a above it, seen by a camera between the two: rho E / pi (1 - a) exactly,
// at depth 1 (the light is a delta: only next-event estimation reaches it).
TEST(Cutout, ShadowRaysPassACutOutInProportion) {
  const double rho = 0.5, irradiance = 2, opacity = 0.4;
  std::string json = R"({"camera": {"position": [0, 0.5, 0], "look_at": [0, 0, 0.01], "up": [0, 0, 1], "fov_y_degrees": 40, "width": 10, "height": 10},
    "materials": {"floor": {"type": "diffuse", "reflectance": [0.5, 0.5, 0.5]},
                  "sheet": {"type": "diffuse", "reflectance": [0, 0, 0], "opacity": 0.4}},
    "shapes": [{"type": "triangles", "material": "floor", "positions": [[-5, 0, -5], [5, 0, -5], [5, 0, 5], [-5, 0, 5]], "indices": [[0, 2, 1], [0, 3, 2]]},
               {"type": "triangles", "material": "sheet", "positions": [[-5, 1, -5], [5, 1, -5], [5, 1, 5], [-5, 1, 5]], "indices": [[0, 2, 1], [0, 3, 2]]}],
    "lights": [{"type": "directional", "direction": [0, -1, 0], "irradiance": [2, 2, 2]}]})";
  DeviceScene scene = load_device_scene(write_temp_file("cutout-shadow.json", json));
  expect_red_everywhere(render_scene(scene, 256, 1).film, rho * irradiance / M_PI * (1 - opacity), "shadow rays");
}

// The decision is a function of the ray and the primitive alone: the 4-, 8- and 16-wide BVHs give the
// same bits.
TEST(Cutout, EveryBvhLayoutGivesTheSameBits) {
  DeviceScene scene = load_device_scene(write_temp_file("cutout-quad.json", quad_in_front_of_the_sky("0.5")));
  std::vector<float> image[3];
  for (int i = 0; i < 3; ++i) {
    BvhWidthScope width(4u << i);
    image[i] = render_scene(scene, 16, 2).film.mean;
  }
  for (int i = 1; i < 3; ++i) {
    ASSERT_EQ(image[0].size(), image[i].size());
    EXPECT_EQ(std::memcmp(image[0].data(), image[i].data(), image[0].size() * sizeof(float)), 0) << (4 << i) << "-wide";
  }
}

// Bad input: an opacity out of range, an opacity texture on a sphere, a cut-out emitter.
TEST(Cutout, BadOpacitiesAreNamed) {
  auto error_of = [](const std::string& json) {
    try {
      load_device_scene(write_temp_file("cutout-bad.json", json));
    } catch (const SceneError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(error_of(quad_in_front_of_the_sky("1.5")).find("materials.black.opacity: expected a number in [0, 1]"),
            std::string::npos);
  write_temp_png("cutout/grey.png", 2, 2, std::vector<unsigned char>(12, 64));
  std::string sphere = R"({"camera": {"position": [0, 0, 3], "look_at": [0, 0, 0], "width": 4, "height": 4},
    "materials": {"m": {"type": "diffuse", "opacity": )";
  EXPECT_NE(error_of(sphere + R"({"texture": "cutout/grey.png"}}}, "shapes": [{"type": "sphere", "radius": 1, "material": "m"}]})")
                .find("spheres do not take"),
            std::string::npos);
  EXPECT_NE(error_of(sphere + R"(0.5}}, "shapes": [{"type": "sphere", "radius": 1, "material": "m", "emission": [1, 1, 1]}]})")
                .find("an emitter cannot be a cut-out"),
            std::string::npos);
}
