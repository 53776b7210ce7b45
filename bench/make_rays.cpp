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

#include "runtime/ray_sets.h"
#include "runtime/ray_trace.h"
#include "scene/device_scene_build.h"
#include "scene/scene_error.h"

namespace {

void write_rays(const std::string& path, const std::vector<RayRecord>& rays) {
  std::ofstream out(path, std::ios::binary);
  out.write(reinterpret_cast<const char*>(rays.data()), std::streamsize(rays.size() * sizeof(RayRecord)));
  if (!out) throw std::runtime_error(path + ": cannot write");
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
      std::vector<RayRecord> camera = read_ray_file(argv[3]);
      std::ifstream in(argv[4], std::ios::binary);
      std::vector<HitRecord> hits(camera.size());
      if (!in.read(reinterpret_cast<char*>(hits.data()), std::streamsize(hits.size() * sizeof(HitRecord))))
        throw std::runtime_error(std::string(argv[4]) + ": expected one hit record per camera ray");
      auto rays = bounce_rays(scene, camera, hits);
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
