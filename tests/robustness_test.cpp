// Hard numerical cases: watertightness of a perturbed closed mesh, rays spawned from surfaces at
// scales from 1e-8 to 1e8, and a camera grazing a diffuse floor inside an emitting enclosure.
// Smooth normals of zero length fall back to the face normal.
// An emitting sphere as large as the scene may be renders like a small one.
// Degenerate triangles and spheres (emitting ones included) never put a NaN in the image.
#include <cmath>
#include <cstring>
#include <random>
#include <sstream>

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include "runtime/ray_trace.h"
#include "runtime/scene_buffers.h"
#include "test_support.h"

namespace {

float bits(uint32_t u) {
  float f;
  std::memcpy(&f, &u, 4);
  return f;
}

std::string scene_json(const std::string& shapes, const std::string& camera = "") {
  return R"({"camera": )" +
         (camera.empty() ? std::string(R"({"position": [0,0,5], "look_at": [0,0,0], "width": 8, "height": 8})") : camera) +
         R"(, "materials": {"m": {"type": "diffuse", "reflectance": [0.5, 0.5, 0.5]},
                            "lamp": {"type": "diffuse", "reflectance": [0, 0, 0]}}, "shapes": [)" + shapes + "]}";
}

std::string triangles_json(const std::vector<glm::dvec3>& v, const std::vector<std::array<int, 3>>& f,
                           const std::string& extra) {
  std::ostringstream s;
  s.precision(17);
  s << R"({"type": "triangles", "positions": [)";
  for (size_t i = 0; i < v.size(); ++i) s << (i ? "," : "") << "[" << v[i].x << "," << v[i].y << "," << v[i].z << "]";
  s << R"(], "indices": [)";
  for (size_t i = 0; i < f.size(); ++i) s << (i ? "," : "") << "[" << f[i][0] << "," << f[i][1] << "," << f[i][2] << "]";
  s << "], " << extra << "}";
  return s.str();
}

// Runs spawn_test (kernels/tests.cl) over 8-float queries.
std::vector<uint32_t> spawn(const DeviceScene& scene, const std::vector<float>& queries, uint32_t mode) {
  ClContext& cl = test_device();
  static KernelProgram program = build_kernel_program(cl, "tests.cl", kernel_options(kFeatureAll));
  BvhBuffers bvh = upload_bvh(cl, scene);
  ClBuffer prims = upload(cl, scene.prims), shading = upload(cl, scene.shading),
           normals = upload(cl, scene.normals), instances = upload(cl, scene.instances), q = upload(cl, queries);
  size_t n = queries.size() / 8;
  ClBuffer out(cl, CL_MEM_WRITE_ONLY, n * 4);
  ClKernel k(program.kernel("spawn_test"));
  cl_uint next = bvh.bind(k, 0);
  k.arg(next, prims.mem);
  k.arg(next + 1, shading.mem);
  k.arg(next + 2, normals.mem);
  k.arg(next + 3, instances.mem);
  k.arg(next + 4, q.mem);
  k.arg(next + 5, cl_uint(mode));
  k.arg(next + 6, out.mem);
  run_kernel(cl, k.k, n);
  std::vector<uint32_t> result(n);
  CL_CHECK(clEnqueueReadBuffer(cl.queue, out.mem, CL_TRUE, 0, n * 4, result.data(), 0, nullptr, nullptr));
  return result;
}

}  // namespace

TEST(Robustness, PerturbedLatLongSphereIsWatertight) {
  // A closed lat-long sphere, every vertex radius perturbed by up to +-10 %.
  const int rings = 48, segments = 96;
  std::mt19937 rng(31);  // with seeds 31, 35 and 36 a pbrt-style t bound once made single rays leak here
  std::uniform_real_distribution<double> jitter(0.9, 1.1);
  std::vector<glm::dvec3> v = {{0, jitter(rng), 0}, {0, -jitter(rng), 0}};
  for (int r = 1; r < rings; ++r)
    for (int s = 0; s < segments; ++s) {
      double theta = M_PI * r / rings, phi = 2 * M_PI * s / segments;
      v.push_back(jitter(rng) * glm::dvec3(std::sin(theta) * std::cos(phi), std::cos(theta), std::sin(theta) * std::sin(phi)));
    }
  auto at = [&](int r, int s) { return 2 + (r - 1) * segments + (s % segments); };
  std::vector<std::array<int, 3>> f;
  for (int s = 0; s < segments; ++s) {
    f.push_back({0, at(1, s + 1), at(1, s)});
    f.push_back({1, at(rings - 1, s), at(rings - 1, s + 1)});
    for (int r = 1; r + 1 < rings; ++r) {
      f.push_back({at(r, s), at(r, s + 1), at(r + 1, s)});
      f.push_back({at(r, s + 1), at(r + 1, s + 1), at(r + 1, s)});
    }
  }
  DeviceScene scene = load_device_scene(write_temp_file("latlong.json", scene_json(triangles_json(v, f, R"("material": "m")"))));
  ASSERT_EQ(scene.triangle_count, f.size());

  std::uniform_real_distribution<float> u(-1, 1), unit(0, 1);
  // Components drawn in separate statements: the order of evaluation of constructor arguments is
  // unspecified, and the ray set must not depend on the compiler.
  auto random_vec = [&] {
    float x = u(rng), y = u(rng), z = u(rng);
    return glm::vec3(x, y, z);
  };
  auto interior = [&] { return random_vec() * 0.3f; };
  std::vector<RayRecord> rays;
  for (int i = 0; i < 100000; ++i) {  // random directions from random interior points
    glm::vec3 o = interior(), d = random_vec();
    rays.push_back({{o.x, o.y, o.z}, 0, {d.x, d.y, d.z}, INFINITY});
  }
  for (int i = 0; i < 100000; ++i) {  // aimed at vertices and at points of shared edges
    const auto& tri = f[rng() % f.size()];
    glm::vec3 a(v[tri[0]]), b(v[tri[1]]);
    glm::vec3 target = i % 2 ? a : a + unit(rng) * (b - a);
    glm::vec3 o = interior(), d = target - o;
    rays.push_back({{o.x, o.y, o.z}, 0, {d.x, d.y, d.z}, INFINITY});
  }
  TraceTiming timing;
  std::vector<HitRecord> hits = trace_ray_records(test_device(), scene, rays, 1, timing);
  size_t misses = 0;
  for (const HitRecord& h : hits) misses += h.prim == PC_INVALID;
  EXPECT_EQ(misses, 0u);
}

TEST(Robustness, SpawnedRaysNeverReHitTheirSurfaceAtAnyScale) {
  // A tilted planar quad of two triangles, at scales 1e-8 .. 1e8 and offsets up to 1e3 times its size.
  struct Placement {
    double scale, offset;
  } placements[] = {{1e-8, 0}, {1e-8, 1e-5}, {1e-4, 0.1}, {1, 0}, {1, 1000}, {1e4, 1e6}, {1e8, 0}, {1e5, 1e8}};
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(0, 1), s(-1, 1);
  for (const Placement& p : placements) {
    glm::dvec3 o(p.offset, -0.7 * p.offset, 0.3 * p.offset);
    glm::dvec3 e1 = glm::normalize(glm::dvec3(1, 0.2, 0.1)) * p.scale, e2 = glm::normalize(glm::dvec3(-0.1, 0.3, 1)) * p.scale;
    std::vector<glm::dvec3> v = {o - e1 - e2, o + e1 - e2, o + e1 + e2, o - e1 + e2};
    // A second, parallel quad facing the first, for shadow rays between the two surfaces.
    glm::dvec3 gap = glm::normalize(glm::cross(e1, e2)) * p.scale * 0.5;
    for (int k = 0; k < 4; ++k) v.push_back(v[k] + gap);
    DeviceScene scene = load_device_scene(write_temp_file(
        "spawn.json", scene_json(triangles_json(v, {{0, 1, 2}, {0, 2, 3}, {4, 6, 5}, {4, 7, 6}}, R"("material": "m")"))));
    ASSERT_EQ(scene.triangle_count, 4u);
    std::vector<float> away, shadows;
    for (int i = 0; i < 20000; ++i) {
      uint32_t prim = i % 2;  // a triangle of the first quad; half the points crowd the shared diagonal
      float a = u(rng), b = (i % 4 < 2) ? u(rng) * (1 - a) : (1 - a) * (1 - 1e-6f * u(rng));
      float dir_sign = i % 3 ? -1.0f : 1.0f;  // away from the second quad, mostly
      glm::vec3 n = glm::normalize(glm::cross(glm::vec3(e1), glm::vec3(e2)));
      float dx = s(rng), dy = s(rng), dz = s(rng);
      glm::vec3 d = glm::normalize(glm::vec3(dx, dy, dz) * 0.9f + n * dir_sign * 1.1f);
      away.insert(away.end(), {bits(scene.leaf_slot[prim]), a, b, d.x, d.y, d.z, 0, 0});
      uint32_t target = 2 + (i % 2);
      shadows.insert(shadows.end(), {bits(scene.leaf_slot[prim]), a, b, bits(scene.leaf_slot[target]), u(rng) * 0.5f,
                                     u(rng) * 0.5f, 0, 0});
    }
    std::vector<uint32_t> hits = spawn(scene, away, 0), blocked = spawn(scene, shadows, 1);
    size_t self_hits = 0, rays_blocked = 0;
    for (size_t i = 0; i < hits.size(); ++i) {
      // Rays leaving towards -n may only reach nothing; towards +n only the second quad (prims 2, 3).
      self_hits += hits[i] == 0 || hits[i] == 1;
      rays_blocked += blocked[i] != PC_INVALID;
    }
    EXPECT_EQ(self_hits, 0u) << "scale " << p.scale << " offset " << p.offset;
    EXPECT_EQ(rays_blocked, 0u) << "scale " << p.scale << " offset " << p.offset;
  }
}

TEST(Robustness, GrazingCameraAboveAFloorSeesRhoTimesLeEverywhere) {
  // A 10 x 10 floor (albedo 0.5) closed by five walls emitting Le = 1 that reflect nothing. With one
  // scattering event every floor point has radiance rho Le = 0.5, whatever the angle it is seen at.
  std::vector<glm::dvec3> v = {{-5, 0, -5}, {5, 0, -5}, {5, 0, 5}, {-5, 0, 5}, {-5, 10, -5}, {5, 10, -5}, {5, 10, 5}, {-5, 10, 5}};
  std::string floor = triangles_json(v, {{0, 2, 1}, {0, 3, 2}}, R"("material": "m")");
  std::string walls = triangles_json(v, {{4, 5, 6}, {4, 6, 7}, {0, 1, 5}, {0, 5, 4}, {1, 2, 6}, {1, 6, 5}, {2, 3, 7}, {2, 7, 6},
                                         {3, 0, 4}, {3, 4, 7}},
                                     R"("material": "lamp", "emission": [1, 1, 1], "two_sided": true)");
  // Camera 1 mm above the floor, pitched down so the top edge of the image is 1 degree below the horizon.
  std::string camera = R"({"position": [0, 0.001, 3], "look_at": [0, -0.2679, 2], "fov_y_degrees": 28,
                           "width": 48, "height": 32})";
  DeviceScene scene = load_device_scene(write_temp_file("grazing.json", scene_json(floor + "," + walls, camera)));
  RenderOptions opt;
  opt.spp = 64;
  opt.max_depth = 1;
  RenderResult r = render(test_device(), scene, opt);
  EXPECT_EQ(r.nan_samples + r.inf_samples + r.negative_samples, 0u);
  size_t pixels = r.film.mean.size() / 3, failures = 0;
  std::vector<double> values;
  for (size_t p = 0; p < pixels; ++p) {
    double m = r.film.mean[3 * p], sd = std::sqrt(r.film.variance[3 * p]);
    values.push_back(m);
    failures += std::abs(m - 0.5) > 3.29 * sd + 1e-6;  // two-sided p = 0.001 per pixel
  }
  // Stated pass rate: at least 99 % of the pixels pass the per-pixel z-test.
  EXPECT_LE(failures, pixels / 100) << failures << " of " << pixels << " pixels fail";
  MeanStd m = mean_and_error(values);
  EXPECT_NEAR(m.mean, 0.5, 4 * m.std_error + 1e-6);
}

namespace {

// No invalid sample was counted and every pixel is finite.
void expect_finite_render(const RenderResult& r) {
  EXPECT_EQ(r.nan_samples, 0u);
  EXPECT_EQ(r.inf_samples, 0u);
  EXPECT_EQ(r.negative_samples, 0u);
  size_t bad = 0;
  for (float v : r.film.mean) bad += !std::isfinite(v);
  for (float v : r.film.variance) bad += !std::isfinite(v);
  EXPECT_EQ(bad, 0u);
}

// An emitting sphere around everything (normals inwards), so that any surface is lit.
const char* kEnclosure = R"({"type": "sphere", "radius": 20, "flip_normals": true, "material": "m", "emission": [1, 1, 1]})";

}  // namespace

TEST(Robustness, ZeroLengthSmoothNormalsFallBackToTheFaceNormal) {
  // A closed surface folded flat into the plane z = 0: the square (0,0)-(2,2) covered on its front by
  // two triangles and on its back by a fan around its centre. At a crease angle of 180 degrees (so that
  // the fold is smoothed over) the angle-weighted normals at the square's four corners cancel exactly (the
  // two sides subtend 90 degrees at each): corners without a normal.
  std::vector<glm::dvec3> v = {{0, 0, 0}, {2, 0, 0}, {2, 2, 0}, {0, 2, 0}, {1, 1, 0}};
  std::string folded = triangles_json(v, {{0, 1, 2}, {0, 2, 3}, {4, 1, 0}, {4, 2, 1}, {4, 3, 2}, {4, 0, 3}},
                                      R"("material": "m", "smooth": true, "smooth_angle_degrees": 180)");
  std::string camera = R"({"position": [1, 0.5, 3], "look_at": [1, 1, 0], "width": 16, "height": 16})";
  std::string path = write_temp_file("folded.json", scene_json(folded + "," + kEnclosure, camera));
  SceneDescription description = load_scene(path);
  const TriangleMesh& mesh = description.shapes[0].mesh;
  ASSERT_EQ(mesh.normals.size(), 6u);
  size_t zero = 0;
  for (const auto& corners : mesh.normals)
    for (const glm::vec3& n : corners) zero += n == glm::vec3(0);
  ASSERT_EQ(zero, 14u) << "the case under test: the 14 triangle corners at the vertices 0 to 3 have no normal";

  DeviceScene scene = build_device_scene(description);
  ASSERT_EQ(scene.normals.size(), 3 * (mesh.triangles.size() + 1));  // + the sphere's unused slots
  for (uint32_t i = 0; i < mesh.triangles.size(); ++i) {
    Primitive p = scene_primitive(scene, i);
    glm::vec3 face = glm::normalize(glm::cross(glm::vec3(p.b.x, p.b.y, p.b.z) - glm::vec3(p.a.x, p.a.y, p.a.z),
                                               glm::vec3(p.c.x, p.c.y, p.c.z) - glm::vec3(p.a.x, p.a.y, p.a.z)));
    // A triangle without a normal at any corner (the front two) is flat: no smooth flag, no normals.
    const bool none = mesh.normals[i] == std::array<glm::vec3, 3>{};
    EXPECT_EQ((scene.shading[i].flags & PC_FLAG_SMOOTH) != 0, !none) << "triangle " << i;
    for (int k = 0; k < 3; ++k) {
      const pc_float4& n = scene.normals[3 * i + k];
      glm::vec3 corner(n.x, n.y, n.z);
      if (none) {
        EXPECT_EQ(corner, glm::vec3(0));
        continue;
      }
      EXPECT_NEAR(glm::length(corner), 1.0f, 1e-6f) << "triangle " << i << " corner " << k;
      // Where the corner had no normal, it has the face's.
      if (mesh.normals[i][k] == glm::vec3(0)) { EXPECT_NEAR(glm::dot(corner, face), 1.0f, 1e-6f); }
    }
  }
  RenderOptions opt;
  opt.spp = 16;
  opt.max_depth = 3;
  RenderResult r = render(test_device(), scene, opt);
  expect_finite_render(r);
}

TEST(Robustness, EmittingSphereAsLargeAsAllowedRendersLikeASmallOne) {
  // A sphere of the largest radius the loader accepts (its area 4 pi r^2 ~ 3e37 is close to float's
  // 3.4e38), emitting Le = 0.5 inwards with albedo 0.5 and seen from its centre: a furnace whose
  // pixels are Le (1 - rho^4) / (1 - rho) for max_depth 3 (tests/furnace_test.cpp), like the same
  // scene with radius 2. Same seed, so the two renders use the same random numbers.
  auto furnace = [](double radius) {
    char sphere[200];
    std::snprintf(sphere, sizeof sphere,
                  R"({"type": "sphere", "radius": %.17g, "flip_normals": true, "material": "m", "emission": [0.5, 0.5, 0.5]})",
                  radius);
    std::string camera = R"({"position": [0, 0, 0], "look_at": [0.5, 0.4, -1], "fov_y_degrees": 100, "width": 16,
                             "height": 16})";
    DeviceScene scene = load_device_scene(write_temp_file("furnace.json", scene_json(sphere, camera)));
    EXPECT_EQ(scene.lights.size(), 1u);
    EXPECT_TRUE(std::isfinite(scene.lights[0].area));
    EXPECT_EQ(scene.light_bvh.size(), 1u);  // the one light is the tree's root
    EXPECT_TRUE(scene.light_bvh[0].lo.w > 0 && std::isfinite(scene.light_bvh[0].lo.w)) << scene.light_bvh[0].lo.w;
    RenderOptions opt;
    opt.spp = 8;
    opt.max_depth = 3;
    return render(test_device(), scene, opt);
  };
  RenderResult small = furnace(2), huge = furnace(kMaxSceneExtent);
  expect_finite_render(huge);
  const double expected = 0.5 * (1 - std::pow(0.5, 4)) / (1 - 0.5);
  double worst = 0, sum = 0;
  for (size_t i = 0; i < huge.film.mean.size(); ++i) {
    worst = std::max(worst, std::abs(double(huge.film.mean[i]) - small.film.mean[i]) / expected);
    sum += huge.film.mean[i];
  }
  // The furnace's own samples are exact to a few 1e-4 (float rounding in the MIS weights: per pixel,
  // 1.04e-4 measured after the local-frame BSDFs); a sphere broken by its size would be off by orders of
  // magnitude, or NaN.
  EXPECT_LT(worst, 3e-4);
  EXPECT_NEAR(sum / huge.film.mean.size(), expected, 1e-4 * expected);
}

TEST(Robustness, DegenerateTrianglesAndSpheresNeverPutANaNInTheImage) {
  // The camera sits at x = z = 0, so that offsets as small as 1e-30 in x and z survive the
  // camera-relative conversion to float. Each case emits, and again without emission: a collinear
  // triangle, one with a repeated vertex (both removed by clean-up), needles 1e-20 and 1e-12 wide, a
  // triangle whose area (~1e-60) underflows float, a sphere of radius 1e-30 (area underflows too), and a
  // triangle of sides 5e-10 (area ~1e-19: light pdfs near 1e20). A floor, all inside an emitting sphere.
  auto tri = [](const std::string& a, const std::string& b, const std::string& c, bool emits) {
    return R"({"type": "triangles", "positions": [)" + a + "," + b + "," + c + R"(], "indices": [[0, 1, 2]],
               "material": "m")" + (emits ? R"(, "emission": [5, 5, 5], "two_sided": true)" : "") + "}";
  };
  std::string shapes = tri("[-4, -1, -5]", "[0, -1, 3]", "[4, -1, -5]", false);  // the floor
  for (bool emits : {true, false}) {
    shapes += "," + tri("[0, 0, -1]", "[1, 0, -1]", "[2, 0, -1]", emits);              // collinear
    shapes += "," + tri("[0, 0.1, -1]", "[1, 0.1, -1]", "[1, 0.1, -1]", emits);        // repeated vertex
    shapes += "," + tri("[0, 0.2, -3]", "[0, 0.2, -0.5]", "[1e-20, 0.2, -1.5]", emits);  // needle
    shapes += "," + tri("[0, 0.3, -3]", "[0, 0.3, -0.5]", "[1e-12, 0.3, -1.5]", emits);  // needle
    shapes += "," + tri("[0, 0.4, 0]", "[1e-30, 0.4, 0]", "[0, 0.4, 1e-30]", emits);   // area underflows
    shapes += "," + tri("[0, 0, 0]", "[5e-10, 0, 0]", "[0, 0, 5e-10]", emits);         // tiny
    shapes += std::string(R"(, {"type": "sphere", "center": [0, 0.6, -1], "radius": 1e-30, "material": "m")") +
              (emits ? R"(, "emission": [5, 5, 5]})" : "}");
  }
  shapes += std::string(",") + kEnclosure;
  std::string camera = R"({"position": [0, 0.5, 0], "look_at": [0, 0, -2], "width": 24, "height": 24})";
  DeviceScene scene = load_device_scene(write_temp_file("degenerate.json", scene_json(shapes, camera)));
  EXPECT_EQ(scene.triangle_count, 1u + 2 * 4);  // the floor and 4 of the 6 triangles, twice
  // The triangle and the sphere whose float areas are 0 are not lights; the needles, the tiny triangle
  // and the enclosure are.
  EXPECT_EQ(scene.skipped_zero_area_emitters, 2u);
  ASSERT_EQ(scene.lights.size(), 4u);
  for (const Light& l : scene.lights) {
    EXPECT_TRUE(l.area > 0 && std::isfinite(l.area));
  }
  for (const LightBvhNode& n : scene.light_bvh) EXPECT_TRUE(n.lo.w >= 0 && std::isfinite(n.lo.w)) << n.lo.w;
  RenderOptions opt;
  opt.spp = 64;
  opt.max_depth = 4;
  RenderResult r = render(test_device(), scene, opt);
  expect_finite_render(r);
}
