// Instances: a mesh that several shapes place is stored once, with a BVH of its own under the instance BVH
// (kernels/intersect.cl, trace_instances), and renders as its flattened copies do.
#include <cmath>
#include <cstdio>
#include <cstring>

#include <gtest/gtest.h>

#include "test_support.h"

namespace {

const std::string kInstances = std::string(PATHCL_TEST_SCENES) + "/instances.json";

size_t mesh_triangles(const std::string& obj) {
  SceneDescription d = load_scene(write_temp_file(
      "count.json", R"({"camera": {"position": [0, 0, 5], "look_at": [0, 0, 0], "width": 8, "height": 8}, "materials": {"m": {"type": "diffuse"}},
                      "shapes": [{"type": "mesh", "file": ")" + obj + R"(", "material": "m"}]})"));
  return d.shapes.at(0).mesh.triangles.size();
}

// A scene placing the icosphere `placements` times in a row over a floor, lit by a quad lamp.
std::string spheres_scene(int placements) {
  std::string shapes =
      R"({"type": "triangles", "positions": [[-20, 0, -4], [20, 0, -4], [20, 0, 4], [-20, 0, 4]], "indices": [[0, 2, 1], [0, 3, 2]], "material": "m"},
         {"type": "triangles", "positions": [[-1, 4, -1], [1, 4, -1], [1, 4, 1], [-1, 4, 1]], "indices": [[0, 1, 2], [0, 2, 3]], "material": "m", "emission": [5, 5, 5]})";
  for (int i = 0; i < placements; ++i)
    shapes += R"(, {"type": "mesh", "file": ")" + std::string(PATHCL_SOURCE_DIR) +
              R"(/scenes/meshes/icosphere-4.obj", "material": "m", "smooth": true, "transform": {"translate": [)" +
              std::to_string(2.2 * i - 16.5) + R"(, 1, 0]}})";
  return R"({"camera": {"position": [0, 3, 14], "look_at": [0, 1, 0], "width": 32, "height": 16}, "materials": {"m": {"type": "diffuse"}}, "shapes": [)" +
         shapes + "]}";
}

std::vector<float> render_scene(const DeviceScene& scene, uint32_t spp, uint32_t seed, Film* film_out = nullptr,
                                 size_t work_group = 0, uint32_t pass_spp = 0, uint32_t max_depth = 5) {
  RenderOptions opt;
  opt.spp = spp;
  opt.max_depth = max_depth;
  opt.seed = seed;
  opt.work_group = work_group;
  opt.pass_spp = pass_spp;
  RenderResult r = render(test_device(), scene, opt);
  if (film_out) *film_out = r.film;
  return r.film.mean;
}

bool bitwise_equal(const std::vector<float>& a, const std::vector<float>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0;
}

}  // namespace

TEST(Instancing, MeshesPlacedMoreThanOnceAreStoredOnce) {
  SceneDescription d = load_scene(kInstances);
  // The red cubes (3 placements), the metal spheres (2) and the cut-out cubes (2): three meshes, each
  // placed by the shapes that name it with the same settings; the floor and the lamp are placed once.
  ASSERT_EQ(d.instanced_meshes.size(), 3u);
  size_t instances = 0;
  for (const ShapeDesc& s : d.shapes)
    if (s.instance_of != PC_INVALID) {
      ++instances;
      EXPECT_TRUE(s.mesh.triangles.empty()) << s.label;
    }
  EXPECT_EQ(instances, 7u);
  const size_t cube = mesh_triangles(std::string(PATHCL_SOURCE_DIR) + "/scenes/meshes/cube.obj");
  const size_t sphere = mesh_triangles(std::string(PATHCL_SOURCE_DIR) + "/scenes/meshes/icosphere-4.obj");
  ASSERT_EQ(cube, 12u);

  DeviceScene kept = build_device_scene(d);
  EXPECT_EQ(kept.instance_count, 7u);
  EXPECT_TRUE(kept.features & kFeatureInstances);
  EXPECT_EQ(kept.triangle_count, 4 + cube + sphere + cube);  // floor and lamp, then each mesh once
  EXPECT_EQ(kept.instanced_triangle_count, 5 * cube + 2 * sphere);
  // The rest of the scene is one more instance, untransformed.
  ASSERT_EQ(kept.instances.size(), 8u);
  size_t identity = 0;
  for (const Instance& inst : kept.instances) identity += inst.flags & PC_INSTANCE_IDENTITY ? 1 : 0;
  EXPECT_EQ(identity, 1u);

  DeviceScene flat = build_device_scene(d, DeviceOrigin::camera, Instancing::flatten);
  EXPECT_EQ(flat.instance_count, 0u);
  EXPECT_FALSE(flat.features & kFeatureInstances);
  EXPECT_EQ(flat.triangle_count, 4 + 5 * cube + 2 * sphere);
}

TEST(Instancing, EmittersAndSinglePlacementsAreNotInstanced) {
  const std::string cube = std::string(PATHCL_SOURCE_DIR) + "/scenes/meshes/cube.obj";
  SceneDescription d = load_scene(write_temp_file(
      "emitters.json", R"({"camera": {"position": [0, 0, 5], "look_at": [0, 0, 0], "width": 8, "height": 8}, "materials": {"m": {"type": "diffuse"}},
        "shapes": [{"type": "mesh", "file": ")" + cube + R"(", "material": "m", "emission": [1, 1, 1]},
                   {"type": "mesh", "file": ")" + cube + R"(", "material": "m", "emission": [1, 1, 1], "transform": {"translate": [2, 0, 0]}},
                   {"type": "mesh", "file": ")" + cube + R"(", "material": "m", "transform": {"translate": [-2, 0, 0]}}]})"));
  EXPECT_TRUE(d.instanced_meshes.empty());
  for (const ShapeDesc& s : d.shapes) {
    EXPECT_EQ(s.instance_of, PC_INVALID);
    EXPECT_EQ(s.mesh.triangles.size(), 12u);
  }
  EXPECT_EQ(build_device_scene(d).lights.size(), 24u);  // every emitting triangle a light, in world space
}

// "instance" decides; without it small meshes stay copies (the Cornell box's two blocks).
TEST(Instancing, TheInstanceKeyDecidesAndSmallMeshesStayCopies) {
  EXPECT_TRUE(load_scene(std::string(PATHCL_SOURCE_DIR) + "/scenes/cornell-box.json").instanced_meshes.empty());
  const std::string cube = std::string(PATHCL_SOURCE_DIR) + "/scenes/meshes/cube.obj";
  auto scene = [&](const std::string& extra) {
    return write_temp_file("key.json", R"({"camera": {"position": [0, 0, 5], "look_at": [0, 0, 0], "width": 8, "height": 8},
      "materials": {"m": {"type": "diffuse"}}, "shapes": [
        {"type": "mesh", "file": ")" + cube + R"(", "material": "m")" + extra + R"(},
        {"type": "mesh", "file": ")" + cube + R"(", "material": "m", "transform": {"translate": [2, 0, 0]})" + extra + "}]}");
  };
  EXPECT_TRUE(load_scene(scene("")).instanced_meshes.empty());
  EXPECT_TRUE(load_scene(scene(R"(, "instance": false)")).instanced_meshes.empty());
  EXPECT_EQ(load_scene(scene(R"(, "instance": true)")).instanced_meshes.size(), 1u);
  EXPECT_NE(scene_load_error(scene(R"(, "instance": true, "emission": [1, 1, 1])")).find(
                "shapes[0].instance: an emitter is not instanced"), std::string::npos);
  EXPECT_NE(scene_load_error(scene(R"(, "instance": 1)")).find("shapes[0].instance: expected"), std::string::npos)
      << scene_load_error(scene(R"(, "instance": 1)"));
}

// 16 placements of one mesh take the memory of one plus the instance table and its BVH.
TEST(Instancing, SixteenPlacementsTakeTheMemoryOfOne) {
  DeviceScene one = build_device_scene(load_scene(write_temp_file("one.json", spheres_scene(1))));
  DeviceScene sixteen = build_device_scene(load_scene(write_temp_file("sixteen.json", spheres_scene(16))));
  DeviceScene flat = build_device_scene(load_scene(write_temp_file("flat.json", spheres_scene(16))), DeviceOrigin::camera,
                                        Instancing::flatten);
  ASSERT_EQ(sixteen.instance_count, 16u);
  ASSERT_EQ(sixteen.triangle_count, one.triangle_count);
  for (uint32_t width : {4u, 8u}) {
    const size_t table = sixteen.instances.size() * sizeof(Instance) + sixteen.instance_bvh.size() * sizeof(BvhNode);
    // The one-placement scene has the sphere and the floor in one tree, the instanced one in two, whose
    // SAH splits (and so leaf sizes and node counts) differ a little: about the memory of one, within 2 %.
    const size_t slack = scene_bytes(one, width) / 50;
    EXPECT_LE(scene_bytes(sixteen, width), scene_bytes(one, width) + table + slack) << width;
    std::printf("%u-wide: one placement %zu bytes, 16 instanced %zu bytes (table %zu), 16 flattened %zu bytes\n", width,
                scene_bytes(one, width), scene_bytes(sixteen, width), table, scene_bytes(flat, width));
    EXPECT_GT(scene_bytes(flat, width), 10 * scene_bytes(one, width)) << width;
  }
}

// The instanced scene renders as its flattened copy, within noise: the two differ only in float rounding
// (the ray taken into each mesh's coordinates). Independent seeds, so the z-test is a real one. Direct
// light alone (depth 1: only the pixel footprint and the lamp's area are sampled, little noise) shows a
// wrongly placed normal or point; depth 5 the indirect light and the cut-outs' transmission.
TEST(Instancing, ImageMatchesTheFlattenedScene) {
  SceneDescription d = load_scene(kInstances);
  DeviceScene kept = build_device_scene(d), flat = build_device_scene(d, DeviceOrigin::camera, Instancing::flatten);
  for (uint32_t depth : {1u, 5u}) {
    Film a, b;
    render_scene(kept, 96, 11, &a, 0, 0, depth);
    render_scene(flat, 96, 12, &b, 0, 0, depth);
    ASSERT_EQ(a.mean.size(), b.mean.size());
    size_t outliers = 0, lit = 0;
    double sum_a = 0, sum_b = 0, var_sum = 0;
    for (size_t i = 0; i < a.mean.size(); ++i) {
      ASSERT_TRUE(std::isfinite(a.mean[i]) && std::isfinite(b.mean[i])) << i;
      sum_a += a.mean[i];
      sum_b += b.mean[i];
      var_sum += a.variance[i] + b.variance[i];
      double se = std::sqrt(a.variance[i] + b.variance[i]);
      if (a.mean[i] > 0 || b.mean[i] > 0) ++lit;
      if (std::abs(a.mean[i] - b.mean[i]) > 4.5 * se + 1e-6f * std::abs(a.mean[i])) ++outliers;
    }
    EXPECT_GT(lit, a.mean.size() / 2) << depth;
    // 4.5 standard errors: about 7e-6 of the values by chance; the image has 3600.
    EXPECT_LE(outliers, 2u) << depth;
    EXPECT_NEAR(sum_a, sum_b, 4 * std::sqrt(var_sum)) << depth;
  }
}

// The surfaces that camera rays meet: an instance's, placed (kernels/surface.cl, place_surface), is its
// flattened copy's within float rounding: the same t, point, geometric and shading normals.
TEST(Instancing, PlacedSurfacesAreTheFlattenedCopiesSurfaces) {
  SceneDescription d = load_scene(kInstances);
  DeviceScene kept = build_device_scene(d), flat = build_device_scene(d, DeviceOrigin::camera, Instancing::flatten);
  const SceneHeader& h = kept.header;
  const int w = 96, hgt = 72;
  std::vector<RayRecord> rays;
  for (int y = 0; y < hgt; ++y)
    for (int x = 0; x < w; ++x) {
      float sx = 2 * (x + 0.5f) / w - 1, sy = 1 - 2 * (y + 0.5f) / hgt;
      RayRecord r{};
      for (int k = 0; k < 3; ++k)
        r.dir[k] = (&h.cam_forward.x)[k] + sx * (&h.cam_right.x)[k] + sy * (&h.cam_up.x)[k];
      r.tmax = INFINITY;
      rays.push_back(r);
    }
  auto trace = [&](const DeviceScene& scene) {
    SceneBuffers sb = test_scene_buffers(scene);
    ClContext& cl = test_device();
    ClBuffer rb = upload(cl, rays), out(cl, CL_MEM_WRITE_ONLY, rays.size() * 12 * sizeof(float));
    ClKernel k(sampling_test_program().kernel("scene_hit_test"));
    cl_uint a = sb.bind(k);
    k.arg(a++, rb.mem);
    k.arg(a++, out.mem);
    run_kernel(cl, k.k, rays.size());
    return read_buffer<float>(cl, out, rays.size() * 12);
  };
  std::vector<float> a = trace(kept), b = trace(flat);
  size_t hits = 0, on_instances = 0, differ = 0;
  for (size_t i = 0; i < rays.size(); ++i) {
    const float* p = &a[12 * i];
    const float* q = &b[12 * i];
    if (std::isinf(p[0]) != std::isinf(q[0])) {  // a silhouette pixel may go either way
      ++differ;
      continue;
    }
    if (std::isinf(p[0])) continue;
    ++hits;
    bool instance = !(kept.instances.at(size_t(p[11])).flags & PC_INSTANCE_IDENTITY);
    on_instances += instance;
    double dt = std::abs(p[0] - q[0]), dp = 0, ng = 0, ns = 0;
    for (int k = 0; k < 3; ++k) {
      dp = std::max(dp, double(std::abs(p[1 + k] - q[1 + k])));
      ng += double(p[4 + k]) * q[4 + k];
      ns += double(p[7 + k]) * q[7 + k];
    }
    // Different surfaces at an edge or behind a cut-out-free overlap count as a difference too.
    if (dt > 1e-4 * q[0] || dp > 1e-4 * q[0] || ng < 0.9999 || ns < 0.999) {
      ++differ;
      continue;
    }
    if (!instance) {  // the rest of the scene is stored alike in both: the same bits
      EXPECT_EQ(p[0], q[0]) << i;
      EXPECT_EQ(p[10], q[10]) << i;
    } else {
      EXPECT_GT(p[10], 0.0f) << i;  // a placed point has an error bound
    }
  }
  EXPECT_GT(on_instances, rays.size() / 8);
  EXPECT_GT(hits, rays.size() / 2);
  EXPECT_LE(differ, rays.size() / 200) << "of " << rays.size();
}

// Bitwise determinism with instances: every BVH layout (each instance's own tree in the device's layout),
// any work-group size and pass split.
TEST(Instancing, PixelsAreTheSameForEveryLayoutWorkGroupAndPassSplit) {
  DeviceScene scene = build_device_scene(load_scene(kInstances));
  std::vector<float> reference;
  {
    BvhWidthScope width(8);
    reference = render_scene(scene, 6, 5);
  }
  for (uint32_t w : {4u, 16u}) {
    BvhWidthScope width(w);
    EXPECT_TRUE(bitwise_equal(render_scene(scene, 6, 5), reference)) << w << "-wide";
  }
  EXPECT_TRUE(bitwise_equal(render_scene(scene, 6, 5, nullptr, 1, 1), reference));
  EXPECT_TRUE(bitwise_equal(render_scene(scene, 6, 5, nullptr, 32, 4), reference));
}

TEST(Instancing, InfoReportsThePlacements) {
  std::string out, err;
  ASSERT_EQ(run_pathcl("info " + kInstances, &err, &out), 0) << err;
  EXPECT_NE(out.find("instances: 7 placements of 3 meshes"), std::string::npos) << out;
  EXPECT_NE(out.find("shapes[2] (../../scenes/meshes/cube.obj): instance of shapes[1] (../../scenes/meshes/cube.obj) (12 triangles)"),
            std::string::npos) << out;
}
