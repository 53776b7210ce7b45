// Makes the ray sets of the traversal benchmark (scripts/bench/own) in pathcl's ray-file format:
//   make_rays camera SCENE.json OUT.rays [SPP]          camera rays, SPP (default 2) jittered per pixel
//   make_rays bounce SCENE.json CAMERA.rays HITS OUT.rays
//                                                       one cosine-weighted diffuse bounce from each hit
// The same files feed `pathcl rays` and other ray tracers, so every tracer sees the same rays.
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <random>
#include <string>

#include <glm/geometric.hpp>

#include "runtime/ray_trace.h"
#include "scene/device_scene_build.h"
#include "scene/scene_error.h"

namespace {

void write_rays(const std::string& path, const std::vector<RayRecord>& rays) {
  std::ofstream out(path, std::ios::binary);
  out.write(reinterpret_cast<const char*>(rays.data()), std::streamsize(rays.size() * sizeof(RayRecord)));
  if (!out) throw std::runtime_error(path + ": cannot write");
}

glm::vec3 v3(const pc_float4& v) { return {v.x, v.y, v.z}; }

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
                                   const std::string& hit_path) {
  std::ifstream in(hit_path, std::ios::binary);
  std::vector<HitRecord> hits(camera.size());
  if (!in.read(reinterpret_cast<char*>(hits.data()), std::streamsize(hits.size() * sizeof(HitRecord))))
    throw std::runtime_error(hit_path + ": expected one hit record per camera ray");
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

}  // namespace

int main(int argc, char** argv) {
  try {
    std::string mode = argc > 1 ? argv[1] : "";
    if (mode == "camera" && (argc == 4 || argc == 5)) {
      DeviceScene scene = build_device_scene(load_scene(argv[2]), DeviceOrigin::world);
      auto rays = camera_rays(scene, argc == 5 ? std::stoi(argv[4]) : 2);
      write_rays(argv[3], rays);
      std::printf("%zu camera rays -> %s\n", rays.size(), argv[3]);
      return 0;
    }
    if (mode == "bounce" && argc == 6) {
      DeviceScene scene = build_device_scene(load_scene(argv[2]), DeviceOrigin::world);
      auto rays = bounce_rays(scene, read_ray_file(argv[3]), argv[4]);
      write_rays(argv[5], rays);
      std::printf("%zu diffuse bounce rays -> %s\n", rays.size(), argv[5]);
      return 0;
    }
    std::fprintf(stderr, "usage: make_rays camera SCENE.json OUT.rays [SPP]\n"
                         "       make_rays bounce SCENE.json CAMERA.rays CAMERA.hits OUT.rays\n");
    return 2;
  } catch (const SceneError& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
}
