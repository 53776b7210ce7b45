#include "runtime/ray_trace.h"

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>

#include "runtime/atomic_file.h"
#include "runtime/kernel_program.h"
#include "runtime/scene_buffers.h"

std::vector<HitRecord> trace_ray_records(ClContext& cl, const DeviceScene& scene, const std::vector<RayRecord>& rays,
                                         int repeat, TraceTiming& timing, size_t work_group, uint32_t lanes,
                                         bool any_hit) {
  if (lanes != 1 && lanes != 8 && lanes != 16)
    throw UsageError("--lanes " + std::to_string(lanes) + ": rays are traced one at a time (1) or as packets of 8 or 16");
  if (lanes > 1 && bvh_width(cl.info) == 4)
    throw UsageError("--lanes " + std::to_string(lanes) + ": packets traverse the 8- or 16-wide BVH, and " +
                     cl.info.name + " uses the 4-wide one");
  KernelProgram program = build_kernel_program(cl, "trace.cl", kernel_options(scene.features));
  timing.kernel_build_ms = program.build_ms;
  timing.kernel_from_cache = program.from_cache;
  std::vector<HitRecord> hits(rays.size());
  if (rays.empty()) return hits;
  // Ray records are in world coordinates. A scene flattened around the camera (DeviceOrigin::camera)
  // gets the ray origins moved by the same offset, in double and then rounded; `pathcl rays` flattens
  // around the world origin, so its rays are traced exactly as written.
  std::vector<RayRecord> moved;
  if (scene.origin != glm::dvec3(0)) {
    moved = rays;
    for (RayRecord& r : moved)
      for (int k = 0; k < 3; ++k) r.org[k] = float(double(r.org[k]) - scene.origin[k]);
  }
  BvhBuffers bvh = upload_bvh(cl, scene);
  ClBuffer prims = upload(cl, scene.prims), ray_buf = upload(cl, moved.empty() ? rays : moved);
  ClBuffer hit_buf(cl, CL_MEM_WRITE_ONLY, sizeof(HitRecord) * rays.size());
  ClKernel kernel(program.kernel(lanes == 1 ? "trace_rays" : lanes == 8 ? "trace_rays_packet8" : "trace_rays_packet16"));
  work_group = kernel_work_group(cl, kernel.k, work_group, lanes, "ray");
  cl_uint next = bvh.bind(kernel, 0);
  kernel.arg(next, prims.mem);
  kernel.arg(next + 1, ray_buf.mem);
  kernel.arg(next + 2, hit_buf.mem);
  kernel.arg(next + 3, cl_uint(rays.size()));
  kernel.arg(next + 4, cl_uint(any_hit));
  for (int r = 0; r < repeat; ++r) {
    auto start = std::chrono::steady_clock::now();
    timing.kernel_ms.push_back(run_kernel(cl, kernel.k, (rays.size() + lanes - 1) / lanes, work_group));
    timing.wall_ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count());
  }
  CL_CHECK(clEnqueueReadBuffer(cl.queue, hit_buf.mem, CL_TRUE, 0, sizeof(HitRecord) * hits.size(), hits.data(), 0,
                               nullptr, nullptr));
  return hits;
}

std::vector<RayRecord> read_ray_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw UsageError(path + ": cannot open the ray file");
  in.seekg(0, std::ios::end);
  size_t bytes = size_t(in.tellg());
  in.seekg(0);
  if (bytes % sizeof(RayRecord) != 0)
    throw UsageError(path + ": size " + std::to_string(bytes) + " is not a multiple of the 32-byte ray record");
  std::vector<RayRecord> rays(bytes / sizeof(RayRecord));
  in.read(reinterpret_cast<char*>(rays.data()), std::streamsize(bytes));
  for (size_t i = 0; i < rays.size(); ++i) {
    const RayRecord& r = rays[i];
    bool finite = std::isfinite(r.org[0]) && std::isfinite(r.org[1]) && std::isfinite(r.org[2]) &&
                  std::isfinite(r.dir[0]) && std::isfinite(r.dir[1]) && std::isfinite(r.dir[2]) && !std::isnan(r.tmin) &&
                  !std::isnan(r.tmax);
    if (!finite || (r.dir[0] == 0 && r.dir[1] == 0 && r.dir[2] == 0))
      throw UsageError(path + ": ray " + std::to_string(i) + " has a non-finite value or a zero direction");
  }
  return rays;
}

void write_hit_file(const std::string& path, const std::vector<HitRecord>& hits) {
  write_binary_file(path, hits.data(), hits.size() * sizeof(HitRecord));
}
