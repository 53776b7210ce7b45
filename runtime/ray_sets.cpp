#include "runtime/ray_sets.h"

#include <cmath>
#include <cstring>
#include <random>

#include <glm/geometric.hpp>

#include "scene/device_scene_build.h"

namespace {

glm::vec3 v3(const pc_float4& v) { return {v.x, v.y, v.z}; }

}  // namespace

std::vector<RayRecord> camera_rays(const DeviceScene& scene, int spp) {
  const SceneHeader& h = scene.header;
  std::mt19937 rng(1);
  std::uniform_real_distribution<float> u(0, 1);
  std::vector<RayRecord> rays;
  for (uint32_t y = 0; y < h.height; ++y)
    for (uint32_t x = 0; x < h.width; ++x)
      for (int s = 0; s < spp; ++s) {
        float sx = 2 * (x + u(rng)) / h.width - 1, sy = 1 - 2 * (y + u(rng)) / h.height;
        glm::vec3 d = glm::normalize(v3(h.cam_forward) + sx * v3(h.cam_right) + sy * v3(h.cam_up));
        glm::vec3 o = v3(h.cam_position);
        rays.push_back({{o.x, o.y, o.z}, 0, {d.x, d.y, d.z}, INFINITY});
      }
  return rays;
}

std::vector<RayRecord> bounce_rays(const DeviceScene& scene, const std::vector<RayRecord>& camera,
                                   const std::vector<HitRecord>& hits) {
  std::mt19937 rng(2);
  std::uniform_real_distribution<float> u(0, 1);
  std::vector<RayRecord> rays;
  for (size_t i = 0; i < hits.size(); ++i) {
    if (hits[i].prim == PC_INVALID) continue;
    const RayRecord& r = camera[i];
    glm::vec3 o(r.org[0], r.org[1], r.org[2]), d(r.dir[0], r.dir[1], r.dir[2]);
    glm::vec3 p = o + hits[i].t * d;
    Primitive prim = scene_primitive(scene, hits[i].prim);
    uint32_t kind;
    std::memcpy(&kind, &prim.b.w, 4);
    glm::vec3 n = kind == PC_PRIM_SPHERE ? glm::normalize(p - v3(prim.a))
                                         : glm::normalize(glm::cross(v3(prim.b) - v3(prim.a), v3(prim.c) - v3(prim.a)));
    if (glm::dot(n, d) > 0) n = -n;
    // Cosine-weighted direction about n.
    float r1 = u(rng), r2 = u(rng), rad = std::sqrt(r1), phi = 2 * float(M_PI) * r2;
    glm::vec3 t = std::abs(n.x) > 0.5f ? glm::vec3(0, 1, 0) : glm::vec3(1, 0, 0);
    glm::vec3 a = glm::normalize(glm::cross(t, n)), b = glm::cross(n, a);
    glm::vec3 w = glm::normalize(rad * std::cos(phi) * a + rad * std::sin(phi) * b + std::sqrt(1 - r1) * n);
    glm::vec3 start = p + n * (1e-4f * std::max(1.0f, glm::length(p)));
    rays.push_back({{start.x, start.y, start.z}, 0, {w.x, w.y, w.z}, INFINITY});
  }
  return rays;
}

