// Ray/box and ray/triangle tests run on the device one by one: edges, vertices, axis-parallel rays,
// degenerate triangles, watertightness across a shared edge.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>

#include <glm/common.hpp>
#include <glm/geometric.hpp>

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

using Boxes = std::vector<std::pair<glm::vec3, glm::vec3>>;

// Runs test kernel `name` over the rays and boxes (ray i against box i): its arguments the rays, the boxes
// (lo.xyz, hi.xyz), scratch_bytes a ray of device memory when nonzero, and one T a ray out.
// program: tests.cl built for the device's own layout where null.
template <class T>
std::vector<T> run_box_kernel(const char* name, const std::vector<RayRecord>& rays, const Boxes& boxes,
                              size_t scratch_bytes = 0, KernelProgram* program = nullptr) {
  ClContext& cl = test_device();
  static KernelProgram own = build_kernel_program(cl, "tests.cl", kernel_options(kFeatureAll));
  if (!program) program = &own;
  std::vector<float> flat;
  for (auto& [lo, hi] : boxes) flat.insert(flat.end(), {lo.x, lo.y, lo.z, hi.x, hi.y, hi.z});
  ClBuffer rb = upload(cl, rays), bb = upload(cl, flat);
  ClBuffer scratch(cl, CL_MEM_READ_WRITE, std::max<size_t>(1, rays.size() * scratch_bytes));
  ClBuffer out(cl, CL_MEM_WRITE_ONLY, rays.size() * sizeof(T));
  ClKernel k(program->kernel(name));
  cl_uint arg = 0;
  k.arg(arg++, rb.mem);
  k.arg(arg++, bb.mem);
  if (scratch_bytes) k.arg(arg++, scratch.mem);
  k.arg(arg, out.mem);
  run_kernel(cl, k.k, rays.size());
  std::vector<T> result(rays.size());
  CL_CHECK(clEnqueueReadBuffer(cl.queue, out.mem, CL_TRUE, 0, result.size() * sizeof(T), result.data(), 0, nullptr,
                               nullptr));
  return result;
}

// Entry distance through the traversal's 4- and 8-box tests, or +inf for a miss (NaN if they disagree).
std::vector<float> box_entries(const std::vector<RayRecord>& rays, const Boxes& boxes) {
  return run_box_kernel<float>("ray_box_test", rays, boxes);
}

// Per ray and box, through the node tests of the 8- or 16-wide layout (width): bit 0 entered by
// ray_boxes_hit8 or 16, bit 1 by the traversal's test (the fused one where it ran), bit 2 the fused test
// ran, bit 3 it is compiled in, bit 4 an empty lane was entered.
std::vector<uint32_t> node_test_entries(const std::vector<RayRecord>& rays, const Boxes& boxes, uint32_t width) {
  BvhWidthScope layout(width);
  KernelProgram program = build_kernel_program(test_device(), "tests.cl", kernel_options(kFeatureAll));
  return run_box_kernel<uint32_t>("ray_box_fused_test", rays, boxes, width == 16 ? sizeof(Bvh16Node) : sizeof(Bvh8Node),
                                  &program);
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

TEST(RayBox, FusedNodeTestEntersTouchedAndCrossedBoxes) {
  // The 8- and 16-wide traversals' fused slab test (kernels/intersect.cl, where fma is an instruction) must
  // enter every box the ray truly reaches within [tmin, tmax], as ray_boxes_hit8 and 16 do, also where it only
  // touches it: at a corner, along an edge, from a corner it starts on, at exactly tmax; near and far
  // from the origin. And it must still miss boxes the ray clearly misses.
  std::vector<RayRecord> rays;
  Boxes boxes;
  std::vector<bool> reached;
  auto add = [&](RayRecord r, glm::vec3 lo, glm::vec3 hi, bool reaches) {
    rays.push_back(r);
    boxes.push_back({lo, hi});
    reached.push_back(reaches);
  };
  for (glm::vec3 at : {glm::vec3(0), glm::vec3(1000.5f, -2000.25f, 333.125f), glm::vec3(-65536, 4096.5f, 1e5f)}) {
    for (glm::vec3 d : {glm::vec3(1, 1, 1), glm::vec3(0.25f, 2, 1), glm::vec3(-3, 1, -0.5f)}) {
      glm::vec3 s = glm::sign(d), p = at + d;  // p: the point at t = 1, exactly representable here
      add(ray(at, d), glm::min(p, p + s), glm::max(p, p + s), true);    // enters at its corner, t = 1
      glm::vec3 e = p + s * glm::vec3(1, -1, 1);                          // touches its edge at t = 1 only
      add(ray(at, d), glm::min(p, e), glm::max(p, e), true);
      add(ray(at, d), glm::min(at, at - s), glm::max(at, at - s), true);  // starts on its corner, leaves
      add(ray(at, d, 0, 1), glm::min(p, p + s), glm::max(p, p + s), true);  // reaches it at tmax exactly
      add(ray(at, d, 0, 0.99f), glm::min(p, p + s), glm::max(p, p + s), false);  // stops before it
      // Beside it: moved along x so that the ray reaches its x slab from t = 2 on, and along y so that the
      // ray has left its y slab at t = -1.
      glm::vec3 q = p + s * glm::vec3(std::abs(d.x), -(2 * std::abs(d.y) + 1), 0);
      add(ray(at, d), glm::min(q, q + s), glm::max(q, q + s), false);
    }
  }
  // Random rays through points of random boxes made as tight as float allows around a point of the ray.
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int i = 0; i < 20000; ++i) {
    double scale = std::pow(10.0, 3 * (i % 3));
    glm::dvec3 o(u(rng) * scale, u(rng) * scale, u(rng) * scale), d(u(rng), u(rng), u(rng));
    if (glm::length(d) < 0.1) continue;
    d *= std::pow(10.0, 2 * u(rng));
    glm::vec3 of(o), df(d);
    double t = 100 * std::abs(u(rng));
    glm::dvec3 q = glm::dvec3(of) + t * glm::dvec3(df);
    glm::vec3 lo, hi;
    for (int k = 0; k < 3; ++k) {
      float down = float(q[k]), up = float(q[k]);
      if (double(down) > q[k]) down = std::nextafter(down, -INFINITY);
      if (double(up) < q[k]) up = std::nextafter(up, INFINITY);
      double grow = i % 2 ? 0 : std::abs(u(rng)) * scale * 1e-3;
      lo[k] = float(down - grow);
      hi[k] = float(up + grow);
      lo[k] = std::min(lo[k], down), hi[k] = std::max(hi[k], up);
    }
    add(ray(of, df), lo, hi, true);
    // The same box moved off the ray by a clear margin across it: missed.
    glm::dvec3 across = glm::normalize(glm::cross(glm::dvec3(df), glm::dvec3(0.3, 0.5, 0.7)));
    glm::dvec3 shift = across * (glm::length(glm::dvec3(hi - lo)) + 1e-3 * (scale + t * glm::length(glm::dvec3(df))));
    add(ray(of, df), glm::vec3(glm::dvec3(lo) + shift), glm::vec3(glm::dvec3(hi) + shift), false);
  }
  for (uint32_t width : {8u, 16u}) {
    auto e = node_test_entries(rays, boxes, width);
    int fused = 0, compiled = 0;
    for (size_t i = 0; i < rays.size(); ++i) {
      ASSERT_EQ(e[i] & 16u, 0u) << width << "-wide, case " << i << ": an empty lane was entered";
      EXPECT_EQ((e[i] & 1u) != 0, bool(reached[i])) << width << "-wide, case " << i << ": ray_boxes_hit" << width;
      EXPECT_EQ((e[i] & 2u) != 0, bool(reached[i])) << width << "-wide, case " << i << ": the traversal's test";
      fused += (e[i] & 4u) != 0;
      compiled += (e[i] & 8u) != 0;
    }
    // Where the fused test is compiled in (PoCL on x86 with FMA), every one of these rays takes it: none is
    // parallel to an axis.
    if (compiled) {
      EXPECT_EQ(fused, int(rays.size()));
    }
    std::printf("%u-wide fused slab test %s: %d of %zu cases\n", width,
                compiled ? "compiled in" : "not compiled in (no fast fma)", fused, rays.size());
  }
}
