// Ray/box and ray/triangle tests run on the device one by one: edges, vertices, axis-parallel rays,
// degenerate triangles, watertightness across a shared edge.
#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "test_support.h"

namespace {

RayRecord ray(glm::vec3 o, glm::vec3 d, float tmin = 0, float tmax = INFINITY) {
  return {{o.x, o.y, o.z}, tmin, {d.x, d.y, d.z}, tmax};
}

struct Tri {
  glm::vec3 a, b, c;
};

std::vector<HitRecord> triangle_hits(const std::vector<RayRecord>& rays, const std::vector<Tri>& tris) {
  ClContext& cl = test_device();
  static KernelProgram program = build_kernel_program(cl, "tests.cl", kernel_options(kFeatureAll));
  std::vector<float> flat;
  for (const Tri& t : tris)
    for (glm::vec3 v : {t.a, t.b, t.c}) flat.insert(flat.end(), {v.x, v.y, v.z});
  ClBuffer rb = upload(cl, rays), tb = upload(cl, flat);
  ClBuffer out(cl, CL_MEM_WRITE_ONLY, rays.size() * sizeof(HitRecord));
  ClKernel k(program.kernel("ray_triangle_test"));
  k.arg(0, rb.mem);
  k.arg(1, tb.mem);
  k.arg(2, out.mem);
  run_kernel(cl, k.k, rays.size());
  std::vector<HitRecord> hits(rays.size());
  CL_CHECK(clEnqueueReadBuffer(cl.queue, out.mem, CL_TRUE, 0, hits.size() * sizeof(HitRecord), hits.data(), 0,
                               nullptr, nullptr));
  return hits;
}

std::vector<float> box_entries(const std::vector<RayRecord>& rays, const std::vector<std::pair<glm::vec3, glm::vec3>>& boxes) {
  ClContext& cl = test_device();
  static KernelProgram program = build_kernel_program(cl, "tests.cl", kernel_options(kFeatureAll));
  std::vector<float> flat;
  for (auto& [lo, hi] : boxes) flat.insert(flat.end(), {lo.x, lo.y, lo.z, hi.x, hi.y, hi.z});
  ClBuffer rb = upload(cl, rays), bb = upload(cl, flat);
  ClBuffer out(cl, CL_MEM_WRITE_ONLY, rays.size() * sizeof(float));
  ClKernel k(program.kernel("ray_box_test"));
  k.arg(0, rb.mem);
  k.arg(1, bb.mem);
  k.arg(2, out.mem);
  run_kernel(cl, k.k, rays.size());
  std::vector<float> t(rays.size());
  CL_CHECK(clEnqueueReadBuffer(cl.queue, out.mem, CL_TRUE, 0, t.size() * 4, t.data(), 0, nullptr, nullptr));
  return t;
}

const Tri kUnit{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};

}  // namespace

TEST(RayTriangle, InteriorHitGivesDistanceAndBarycentrics) {
  auto h = triangle_hits({ray({0.25f, 0.5f, 2}, {0, 0, -1})}, {kUnit});
  ASSERT_EQ(h[0].prim, 0u);
  EXPECT_FLOAT_EQ(h[0].t, 2.0f);
  EXPECT_FLOAT_EQ(h[0].u, 0.25f);  // weight of vertex b = (1,0,0)
  EXPECT_FLOAT_EQ(h[0].v, 0.5f);   // weight of vertex c = (0,1,0)
}

TEST(RayTriangle, BothSidesHitAndOutsideMisses) {
  auto h = triangle_hits({ray({0.2f, 0.2f, -1}, {0, 0, 1}), ray({0.6f, 0.6f, 1}, {0, 0, -1}),
                          ray({-0.01f, 0.5f, 1}, {0, 0, -1}), ray({0.2f, 0.2f, 1}, {0, 0, 1})},
                         {kUnit, kUnit, kUnit, kUnit});
  EXPECT_EQ(h[0].prim, 0u);              // from behind
  EXPECT_EQ(h[1].prim, PC_INVALID);      // beyond the hypotenuse
  EXPECT_EQ(h[2].prim, PC_INVALID);      // left of the edge x = 0
  EXPECT_EQ(h[3].prim, PC_INVALID);      // pointing away
}

TEST(RayTriangle, EdgesAndVerticesAreHit) {
  std::vector<RayRecord> rays = {ray({0.5f, 0, 1}, {0, 0, -1}),   ray({0, 0.5f, 1}, {0, 0, -1}),
                                 ray({0.5f, 0.5f, 1}, {0, 0, -1}), ray({0, 0, 1}, {0, 0, -1}),
                                 ray({1, 0, 1}, {0, 0, -1}),       ray({0, 1, 1}, {0, 0, -1})};
  auto h = triangle_hits(rays, std::vector<Tri>(rays.size(), kUnit));
  for (size_t i = 0; i < rays.size(); ++i) {
    EXPECT_EQ(h[i].prim, 0u) << "ray " << i;
    EXPECT_FLOAT_EQ(h[i].t, 1.0f) << "ray " << i;
  }
}

TEST(RayTriangle, RangeLimitsAreRespected) {
  auto h = triangle_hits({ray({0.2f, 0.2f, 2}, {0, 0, -1}, 0, 1.5f), ray({0.2f, 0.2f, 2}, {0, 0, -1}, 2.5f, 9),
                          ray({0.2f, 0.2f, 2}, {0, 0, -1}, 1.5f, 2.5f)},
                         {kUnit, kUnit, kUnit});
  EXPECT_EQ(h[0].prim, PC_INVALID);
  EXPECT_EQ(h[1].prim, PC_INVALID);
  EXPECT_EQ(h[2].prim, 0u);
}

TEST(RayTriangle, AxisParallelAndInPlaneRays) {
  // Rays along each axis into axis-aligned triangles, and rays lying in the triangle's plane.
  std::vector<RayRecord> rays = {ray({0.2f, 0.2f, 5}, {0, 0, -1}), ray({5, 0.2f, 0.2f}, {-1, 0, 0}),
                                 ray({0.2f, -5, 0.2f}, {0, 1, 0}), ray({-1, 0.2f, 0}, {1, 0, 0})};
  std::vector<Tri> tris = {kUnit, {{0, 0, 0}, {0, 1, 0}, {0, 0, 1}}, {{0, 0, 0}, {0, 0, 1}, {1, 0, 0}}, kUnit};
  auto h = triangle_hits(rays, tris);
  EXPECT_FLOAT_EQ(h[0].t, 5.0f);
  EXPECT_FLOAT_EQ(h[1].t, 5.0f);
  EXPECT_FLOAT_EQ(h[2].t, 5.0f);
  EXPECT_EQ(h[3].prim, PC_INVALID);  // in the plane: no area is crossed
}

TEST(RayTriangle, CollinearAndPointTrianglesAreNeverHit) {
  std::vector<Tri> tris = {{{0, 0, 0}, {1, 1, 0}, {2, 2, 0}}, {{0, 0, 0}, {0, 0, 0}, {0, 0, 0}},
                           {{0, 0, 0}, {1, 0, 0}, {1, 0, 0}}};
  std::vector<RayRecord> rays = {ray({1, 1, 1}, {0, 0, -1}), ray({0, 0, 1}, {0, 0, -1}), ray({0.5f, 0, 1}, {0, 0, -1})};
  auto h = triangle_hits(rays, tris);
  for (size_t i = 0; i < h.size(); ++i) {
    EXPECT_EQ(h[i].prim, PC_INVALID) << "ray " << i;
    EXPECT_FALSE(std::isnan(h[i].t));
  }
}

TEST(RayTriangle, SharedEdgeIsWatertight) {
  // Two triangles share the diagonal of a skewed planar quad far from the origin; rays aimed at points
  // of the diagonal (as near as float allows), from many directions, must hit at least one of the two.
  glm::vec3 p0(1000.1f, -20.3f, 7.7f), p1(1001.7f, -19.9f, 7.7f), p2(1000.9f, -18.2f, 7.7f), p3(999.4f, -18.9f, 7.7f);
  Tri t0{p0, p1, p2}, t1{p0, p2, p3};
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(0, 1);
  std::vector<RayRecord> rays;
  for (int i = 0; i < 20000; ++i) {
    glm::vec3 target = p0 + u(rng) * (p2 - p0);
    glm::vec3 origin = target + glm::vec3(u(rng) - 0.5f, u(rng) - 0.5f, (u(rng) + 0.2f) * (i % 2 ? 1 : -1)) * 10.0f;
    rays.push_back(ray(origin, target - origin));
  }
  std::vector<RayRecord> both(rays);
  both.insert(both.end(), rays.begin(), rays.end());
  std::vector<Tri> tris(rays.size(), t0);
  tris.insert(tris.end(), rays.size(), t1);
  auto h = triangle_hits(both, tris);
  int leaks = 0;
  for (size_t i = 0; i < rays.size(); ++i) leaks += h[i].prim == PC_INVALID && h[i + rays.size()].prim == PC_INVALID;
  EXPECT_EQ(leaks, 0);
}

TEST(RayBox, HitsMissesAndAxisParallelRays) {
  glm::vec3 lo(-1, -1, -1), hi(1, 1, 1);
  std::vector<RayRecord> rays = {
      ray({-5, 0, 0}, {1, 0, 0}),          // axis-parallel through the middle: enters at 4
      ray({-5, 1, 0}, {1, 0, 0}),          // along the face y = 1: boundary counts as inside
      ray({-5, 1.001f, 0}, {1, 0, 0}),     // just above: misses
      ray({0, 0, 0}, {0, 0, 1}),           // starts inside: entry is tmin
      ray({-5, 0, 0}, {-1, 0, 0}),         // points away
      ray({-5, 0, 0}, {1, 0, 0}, 0, 3.9f), // tmax before the box
      ray({-5, -5, -5}, {1, 1, 1}),        // diagonal through the corners
      ray({-1, -1, 5}, {0, 0, -1}),        // along an edge
  };
  auto t = box_entries(rays, std::vector<std::pair<glm::vec3, glm::vec3>>(rays.size(), {lo, hi}));
  EXPECT_FLOAT_EQ(t[0], 4.0f);
  EXPECT_FLOAT_EQ(t[1], 4.0f);
  EXPECT_EQ(t[2], INFINITY);
  EXPECT_FLOAT_EQ(t[3], 0.0f);
  EXPECT_EQ(t[4], INFINITY);
  EXPECT_EQ(t[5], INFINITY);
  EXPECT_FLOAT_EQ(t[6], 4.0f);
  EXPECT_FLOAT_EQ(t[7], 4.0f);
  for (float v : t) EXPECT_FALSE(std::isnan(v));
}

TEST(RayBox, FlatBoxOfAnAxisAlignedTriangleIsEntered) {
  // A box with zero thickness (the bounds of a triangle in the plane z = 0) must still be entered.
  auto t = box_entries({ray({0.5f, 0.5f, 3}, {0, 0, -1}), ray({0.5f, 0.5f, 3}, {0.1f, 0, -1})},
                       {{{0, 0, 0}, {1, 1, 0}}, {{0, 0, 0}, {1, 1, 0}}});
  EXPECT_FLOAT_EQ(t[0], 3.0f);
  EXPECT_NEAR(t[1], 3.0f, 1e-5f);
}
