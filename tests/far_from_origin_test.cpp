// Far from the origin and at odd scales: the Cornell box translated by 1e4, 1e5 and 1e6 or scaled by
// 1e-3 and 1e3, its camera moved with it, must render statistically the same image as the original.
// Float spacing is 0.0625 at 1e6, so this holds only because transforms are composed in double and the
// device scene is camera-relative (scene/device_scene_build.cpp).
#include <cmath>
#include <cstdio>
#include <fstream>

#include <glm/vec3.hpp>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "runtime/image_compare.h"
#include "runtime/ray_trace.h"
#include "test_support.h"

namespace {

using nlohmann::json;

struct Placement {
  const char* name;
  double scale;
  glm::dvec3 offset;
};

// A generic direction (no zero or equal components), with fractions that are not dyadic.
glm::dvec3 far(double distance) { return glm::dvec3(1.0, -0.6, 0.8) * distance + glm::dvec3(0.1234, 0.5678, 0.9012); }

// The bundled Cornell box at 32x32, placed by p: every shape's transform T R S becomes
// T(offset + scale t) R S(scale s) (a uniform scale commutes with the rotation), and the camera's
// position and look_at move the same way.
std::string placed_cornell_box(const Placement& p) {
  const std::string dir = std::string(PATHCL_SOURCE_DIR) + "/scenes";
  json scene = json::parse(std::ifstream(dir + "/cornell-box.json"));
  auto place = [&](const json& v) {
    json out = json::array();
    for (int k = 0; k < 3; ++k) out.push_back(p.offset[k] + p.scale * v[k].get<double>());
    return out;
  };
  json& camera = scene["camera"];
  camera["position"] = place(camera["position"]);
  camera["look_at"] = place(camera["look_at"]);
  camera["width"] = 32;
  camera["height"] = 32;
  for (json& shape : scene["shapes"]) {
    shape["file"] = dir + "/" + shape["file"].get<std::string>();
    json transform = shape.value("transform", json::object());
    transform["translate"] = place(transform.value("translate", json::array({0, 0, 0})));
    json scale = transform.value("scale", json(1.0));
    if (scale.is_array())
      for (json& s : scale) s = s.get<double>() * p.scale;
    else
      scale = scale.get<double>() * p.scale;
    transform["scale"] = scale;
    shape["transform"] = transform;
  }
  return scene.dump();
}

RenderResult render_placed(const Placement& p, uint32_t seed) {
  DeviceScene scene = load_device_scene(write_temp_file(std::string(p.name) + ".json", placed_cornell_box(p)));
  RenderOptions opt;
  opt.spp = 64;
  opt.max_depth = 4;
  opt.seed = seed;
  return render(test_device(), scene, opt);
}

Image image_of(const Film& film) {
  Image image;
  image.width = film.width;
  image.height = film.height;
  image.rgb = film.mean;
  return image;
}

}  // namespace

TEST(FarFromOrigin, TranslatedAndScaledCornellBoxesRenderTheSameImage) {
  const Placement original{"original", 1, {0, 0, 0}};
  const Placement placements[] = {
      {"translated-1e4", 1, far(1e4)},    {"translated-1e5", 1, far(1e5)}, {"translated-1e6", 1, far(1e6)},
      {"scaled-1e-3", 1e-3, {0, 0, 0}},   {"scaled-1e3", 1e3, {0, 0, 0}},
      {"scaled-1e3-translated-1e6", 1e3, far(1e6)},
  };
  RenderResult reference = render_placed(original, 1);
  for (const Placement& p : placements) {
    SCOPED_TRACE(p.name);
    RenderResult r = render_placed(p, 2);  // another seed: the two renders are independent
    EXPECT_EQ(r.nan_samples + r.inf_samples + r.negative_samples, 0u);
    // Per-pixel z-test of the difference against the variance of the difference (the sum of the two
    // means' variances), 4 standard errors: a correct render fails a pixel with probability ~2e-4.
    Image test = image_of(r.film);
    test.variance.resize(r.film.variance.size());
    for (size_t i = 0; i < test.variance.size(); ++i) test.variance[i] = r.film.variance[i] + reference.film.variance[i];
    ImageErrors e = compare_images(image_of(reference.film), test, nullptr, 4.0);
    // The image means (all channels) agree within 4 standard errors too: a small bias spread over many
    // pixels, such as light leaking through shifted walls, fails here before it fails the pixels.
    double sum_d = 0, sum_var = 0;
    for (size_t i = 0; i < test.rgb.size(); ++i) {
      sum_d += double(test.rgb[i]) - reference.film.mean[i];
      sum_var += test.variance[i];
    }
    double z_mean = sum_d / std::sqrt(sum_var);
    std::printf("%-28s %5.2f %% of pixels beyond 4 standard errors, image mean z = %+.2f\n", p.name,
                100 * e.z_fail_fraction, z_mean);
    // Stated pass rate: at least 99 % of the pixels within 4 standard errors.
    EXPECT_LE(e.z_fail_fraction, 0.01);
    EXPECT_LT(std::abs(z_mean), 4.0);
  }
}

TEST(FarFromOrigin, RayRecordsAreInWorldCoordinatesWhateverTheDeviceOrigin) {
  // Rays from the camera at the centroid of every triangle of the Cornell box 1e3 away, given in world
  // coordinates: the camera-relative scene (ray origins moved on upload) and the world-origin scene of
  // `pathcl rays` must find the same primitives at the same distances.
  const Placement p{"rays-1e3", 1, far(1e3)};
  SceneDescription description = load_scene(write_temp_file("rays.json", placed_cornell_box(p)));
  DeviceScene relative = build_device_scene(description), world = build_device_scene(description, DeviceOrigin::world);
  ASSERT_NE(relative.origin, world.origin);
  glm::vec3 o(description.camera.position);
  std::vector<RayRecord> rays;
  for (const ShapeDesc& shape : description.shapes)
    for (const auto& t : shape.mesh.triangles) {
      glm::dvec3 centroid = (shape.mesh.positions[t[0]] + shape.mesh.positions[t[1]] + shape.mesh.positions[t[2]]) / 3.0;
      glm::vec3 d(centroid - glm::dvec3(o));
      rays.push_back({{o.x, o.y, o.z}, 0, {d.x, d.y, d.z}, INFINITY});
    }
  TraceTiming timing;
  std::vector<HitRecord> a = trace_ray_records(test_device(), relative, rays, 1, timing),
                         b = trace_ray_records(test_device(), world, rays, 1, timing);
  size_t hits = 0;
  for (size_t i = 0; i < rays.size(); ++i) {
    hits += a[i].prim != PC_INVALID;
    EXPECT_EQ(a[i].prim, b[i].prim) << "ray " << i;
    EXPECT_NEAR(a[i].t, b[i].t, 1e-4 * b[i].t) << "ray " << i;
  }
  EXPECT_GT(hits, rays.size() / 2);
}
