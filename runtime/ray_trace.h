// Tracing a ray file with the renderer's own traversal code (`pathcl rays`).
#pragma once
#include <string>
#include <vector>

#include "runtime/device.h"
#include "scene/device_scene.h"

struct TraceTiming {
  std::vector<double> kernel_ms, wall_ms;  // one entry per repeat
  double kernel_build_ms = 0;
  bool kernel_from_cache = false;
};

// Traces every ray `repeat` times (the hits of the last repeat are returned). Rays are in world
// coordinates, whatever the scene's DeviceOrigin. lanes 8 or 16: as packets of that many consecutive rays
// (kernels/packet.cl; the 8- and 16-wide BVHs only), with the hits of lanes = 1, one ray per work item. any_hit:
// each ray's first hit found (shadow rays), of which only whether there is one is defined.
std::vector<HitRecord> trace_ray_records(ClContext& cl, const DeviceScene& scene, const std::vector<RayRecord>& rays,
                                         int repeat, TraceTiming& timing, size_t work_group = 0, uint32_t lanes = 1,
                                         bool any_hit = false);

// Ray and hit files: flat little-endian arrays of RayRecord / HitRecord. Reading checks the size.
std::vector<RayRecord> read_ray_file(const std::string& path);  // throws UsageError on a bad file
void write_hit_file(const std::string& path, const std::vector<HitRecord>& hits);  // RuntimeFailure on I/O
