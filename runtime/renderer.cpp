#include "runtime/renderer.h"

#include <algorithm>
#include <chrono>

#include "runtime/kernel_program.h"

RenderResult render(ClContext& cl, const DeviceScene& scene, const RenderOptions& options,
                    const ProgressFn& progress) {
  RenderResult result;
  SceneHeader header = scene.header;
  header.max_depth = options.max_depth;
  header.seed = options.seed;
  header.rr_depth = options.rr_depth;
  result.width = header.width;
  result.height = header.height;
  result.spp = options.spp;
  const size_t pixels = size_t(header.width) * header.height;

  KernelProgram program =
      build_kernel_program(cl, "integrator.cl", kernel_options(options.all_features ? kFeatureAll : scene.features));
  result.kernel_build_ms = program.build_ms;
  result.kernel_from_cache = program.from_cache;
  result.kernel_options = program.options;

  auto start = std::chrono::steady_clock::now();
  ClBuffer header_buf(cl, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, sizeof header, &header);
  ClBuffer nodes = upload(cl, scene.nodes), prims = upload(cl, scene.prims), shading = upload(cl, scene.shading),
           normals = upload(cl, scene.normals), materials = upload(cl, scene.materials),
           lights = upload(cl, scene.lights), cdf = upload(cl, scene.light_cdf);
  ClBuffer film(cl, CL_MEM_READ_WRITE, pixels * sizeof(pc_float4));
  ClBuffer stats(cl, CL_MEM_WRITE_ONLY, pixels * sizeof(PassStats));
  const pc_float4 zero{0, 0, 0, 0};
  CL_CHECK(clEnqueueFillBuffer(cl.queue, film.mem, &zero, sizeof zero, 0, pixels * sizeof zero, 0, nullptr, nullptr));

  ClKernel kernel(program.kernel("render_pass"));
  cl_mem args[] = {header_buf.mem, nodes.mem, prims.mem, shading.mem, normals.mem,
                   materials.mem,  lights.mem, cdf.mem,  film.mem,    stats.mem};
  for (cl_uint i = 0; i < 10; ++i) kernel.arg(i, args[i]);

  uint32_t pass_spp = options.pass_spp;
  if (pass_spp == 0) pass_spp = uint32_t(std::clamp<size_t>((size_t(1) << 20) / std::max<size_t>(pixels, 1), 1, 64));
  std::vector<PassStats> pass_stats(pixels);
  for (uint32_t done = 0; done < options.spp;) {
    uint32_t count = std::min(pass_spp, options.spp - done);
    kernel.arg(10, done);
    kernel.arg(11, count);
    result.kernel_ms += run_kernel(cl, kernel.k, pixels, options.work_group);
    CL_CHECK(clEnqueueReadBuffer(cl.queue, stats.mem, CL_TRUE, 0, pixels * sizeof(PassStats), pass_stats.data(), 0,
                                 nullptr, nullptr));
    for (const PassStats& s : pass_stats) {
      result.rays += s.rays;
      result.nan_samples += s.nan_samples;
      result.inf_samples += s.inf_samples;
      result.negative_samples += s.negative_samples;
    }
    done += count;
    result.passes++;
    if (progress)
      progress(done, options.spp, std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  }

  std::vector<pc_float4> sums(pixels);
  CL_CHECK(clEnqueueReadBuffer(cl.queue, film.mem, CL_TRUE, 0, pixels * sizeof(pc_float4), sums.data(), 0, nullptr,
                               nullptr));
  result.rgb.resize(pixels * 3);
  for (size_t i = 0; i < pixels; ++i) {
    float n = sums[i].w > 0 ? sums[i].w : 1;
    result.rgb[3 * i] = sums[i].x / n;
    result.rgb[3 * i + 1] = sums[i].y / n;
    result.rgb[3 * i + 2] = sums[i].z / n;
  }
  result.render_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}
