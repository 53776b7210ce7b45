// The ray sets of the traversal benchmarks (`pathcl bench`, bench/make_rays for scripts/bench/): camera
// rays jittered in every pixel and one cosine-weighted diffuse bounce from each hit. Deterministic:
// fixed seeds, so every tracer and every run sees the same rays. World coordinates.
#pragma once
#include <vector>

#include "scene/device_scene.h"

std::vector<RayRecord> camera_rays(const DeviceScene& scene, int spp);
// One bounce ray from the hit of each camera ray that hit something.
std::vector<RayRecord> bounce_rays(const DeviceScene& scene, const std::vector<RayRecord>& camera,
                                   const std::vector<HitRecord>& hits);
