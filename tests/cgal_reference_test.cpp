// Hard cases against CGAL's AABB tree with exact predicates: rays aimed at the vertices and edges of
// closed meshes. Where CGAL decides (exactly, for the same float ray) that the ray meets the mesh,
// the renderer's traversal must hit it too, at the same distance.
#include <random>

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <gtest/gtest.h>

#include "runtime/ray_trace.h"
#include "test_support.h"

namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Tri3 = K::Triangle_3;
using Tree = CGAL::AABB_tree<CGAL::AABB_traits<K, CGAL::AABB_triangle_primitive<K, std::vector<Tri3>::iterator>>>;

K::Point_3 point(const pc_float4& v) { return {v.x, v.y, v.z}; }

struct Comparison {
  size_t cgal_hits = 0, missed = 0, distance_off = 0;
};

// The scene keeps the world origin (DeviceOrigin::world): CGAL gets its triangles and the rays as they are.
Comparison compare_with_cgal(const DeviceScene& scene, const std::vector<RayRecord>& rays) {
  std::vector<Tri3> tris;
  for (uint32_t i = 0; i < scene.triangle_count; ++i) {
    Primitive p = scene_primitive(scene, i);
    tris.emplace_back(point(p.a), point(p.b), point(p.c));
  }
  Tree tree(tris.begin(), tris.end());
  TraceTiming timing;
  std::vector<HitRecord> hits = trace_ray_records(test_device(), scene, rays, 1, timing);
  Comparison c;
  for (size_t i = 0; i < rays.size(); ++i) {
    const RayRecord& r = rays[i];
    K::Ray_3 ray(K::Point_3(r.org[0], r.org[1], r.org[2]), K::Vector_3(r.dir[0], r.dir[1], r.dir[2]));
    if (!tree.do_intersect(ray)) continue;  // exact predicate
    ++c.cgal_hits;
    if (hits[i].prim == PC_INVALID) {
      if (++c.missed < 5) ADD_FAILURE() << "ray " << i << " slipped through the mesh";
      continue;
    }
    auto first = tree.first_intersection(ray);
    const K::Point_3* p = first ? boost::get<K::Point_3>(&first->first) : nullptr;
    if (!p) continue;  // a segment overlap: no single distance to compare
    double t = std::sqrt(CGAL::to_double(CGAL::squared_distance(ray.source(), *p))) /
               std::sqrt(CGAL::to_double(ray.to_vector().squared_length()));
    if (std::abs(t - hits[i].t) > 1e-4 * std::max(1.0, t) && ++c.distance_off < 5)
      ADD_FAILURE() << "ray " << i << ": CGAL t=" << t << ", pathcl t=" << hits[i].t;
  }
  return c;
}

std::string closed_scene(const std::string& shape) {
  return R"({"camera": {"position": [0,0,5], "look_at": [0,0,0], "width": 8, "height": 8},
    "materials": {"m": {"type": "diffuse"}}, "shapes": [)" + shape + R"(, "material": "m"}]})";
}

}  // namespace

TEST(CgalReference, RaysAtIcosphereVerticesAndEdgesFromInside) {
  DeviceScene scene =
      load_device_scene(write_temp_file("ico.json", closed_scene(icosphere_json(1.5f, 2, false))), DeviceOrigin::world);
  std::mt19937 rng(17);
  std::uniform_real_distribution<float> u(-0.5f, 0.5f), w(0, 1);
  std::vector<RayRecord> rays;
  for (uint32_t i = 0; i < scene.triangle_count; ++i) {
    Primitive p = scene_primitive(scene, i);
    glm::vec3 a(p.a.x, p.a.y, p.a.z), b(p.b.x, p.b.y, p.b.z);
    for (glm::vec3 target : {a, a + w(rng) * (b - a), 0.5f * (a + b)}) {
      glm::vec3 o(u(rng), u(rng), u(rng));
      glm::vec3 d = target - o;
      rays.push_back({{o.x, o.y, o.z}, 0, {d.x, d.y, d.z}, INFINITY});
    }
  }
  Comparison c = compare_with_cgal(scene, rays);
  EXPECT_EQ(c.cgal_hits, rays.size());  // from inside a closed mesh every ray meets it
  EXPECT_EQ(c.missed, 0u);
  EXPECT_EQ(c.distance_off, 0u);
}

TEST(CgalReference, RaysAtCubeVerticesAndEdgesFromOutside) {
  std::string cube = R"({"type": "mesh", "file": ")" + std::string(PATHCL_TEST_SCENES) +
                     R"(/../../scenes/meshes/cube.obj", "transform": {"scale": 2})";
  DeviceScene scene = load_device_scene(write_temp_file("cube.json", closed_scene(cube)), DeviceOrigin::world);
  ASSERT_EQ(scene.triangle_count, 12u);
  std::mt19937 rng(23);
  std::uniform_real_distribution<float> away(0.5f, 5), free(-3, 3), s(0, 1);
  std::vector<RayRecord> rays;
  for (int i = 0; i < 20000; ++i) {
    // Vertices are (+-1, +-1, +-1); edge points have two coordinates at +-1. The origin lies beyond the
    // target on every pinned axis, so the ray enters the cube through that vertex or edge (no grazing).
    glm::vec3 target(s(rng) < 0.5f ? -1 : 1, s(rng) < 0.5f ? -1 : 1, s(rng) < 0.5f ? -1 : 1);
    glm::vec3 o;
    for (int k = 0; k < 3; ++k) o[k] = target[k] * (1 + away(rng));
    if (i % 2) {
      target[i % 3] = 2 * s(rng) - 1;
      o[i % 3] = free(rng);
    }
    glm::vec3 d = target - o;
    rays.push_back({{o.x, o.y, o.z}, 0, {d.x, d.y, d.z}, INFINITY});
  }
  Comparison c = compare_with_cgal(scene, rays);
  EXPECT_GT(c.cgal_hits, rays.size() * 9 / 10);  // the rest pass an ulp outside, exactly decided
  EXPECT_EQ(c.missed, 0u);
  EXPECT_EQ(c.distance_off, 0u);
}
