#include "runtime/renderer.h"

#include <algorithm>
#include <chrono>
#include <optional>

#include "runtime/kernel_program.h"

namespace {

Film read_film(ClContext& cl, const ClBuffer& film_buf, uint32_t width, uint32_t height) {
  std::vector<pc_float4> acc(3 * size_t(width) * height);
  CL_CHECK(clEnqueueReadBuffer(cl.queue, film_buf.mem, CL_TRUE, 0, acc.size() * sizeof(pc_float4), acc.data(), 0,
                               nullptr, nullptr));
  return film_from_accumulators(width, height, std::move(acc));
}

}  // namespace

Film film_from_accumulators(uint32_t width, uint32_t height, std::vector<pc_float4> acc) {
  size_t pixels = size_t(width) * height;
  Film f;
  f.width = width;
  f.height = height;
  f.mean.resize(3 * pixels);
  f.variance.resize(3 * pixels);
  f.even_mean.resize(3 * pixels);
  f.odd_mean.resize(3 * pixels);
  for (size_t p = 0; p < pixels; ++p) {
    const pc_float4 &even = acc[3 * p], &odd = acc[3 * p + 1], &sq = acc[3 * p + 2];
    double n = double(even.w) + odd.w;
    f.spp = uint32_t(n);
    const float e[3] = {even.x, even.y, even.z}, o[3] = {odd.x, odd.y, odd.z}, s[3] = {sq.x, sq.y, sq.z};
    for (int c = 0; c < 3; ++c) {
      double sum = double(e[c]) + o[c];
      double mean = n > 0 ? sum / n : 0;
      f.mean[3 * p + c] = float(mean);
      f.even_mean[3 * p + c] = even.w > 0 ? e[c] / even.w : 0.0f;
      f.odd_mean[3 * p + c] = odd.w > 0 ? o[c] / odd.w : 0.0f;
      double sample_variance = n > 1 ? std::max(0.0, (s[c] - sum * mean) / (n - 1)) : 0.0;
      f.variance[3 * p + c] = float(n > 0 ? sample_variance / n : 0.0);
    }
  }
  f.accumulators = std::move(acc);
  return f;
}

LaunchSize adapt_launch_size(LaunchSize size, double slowest_launch_ms, size_t pixels) {
  // Too slow: fewer samples per launch first, then fewer pixels (in steps of 1024, at least 1024).
  // Too fast: more pixels first (up to the whole film), then more samples (up to 256).
  if (slowest_launch_ms > 100 && size.pass_spp > 1) size.pass_spp /= 2;
  else if (slowest_launch_ms > 100) size.launch_pixels = std::max<size_t>(size.launch_pixels / 2 / 1024 * 1024, 1024);
  else if (slowest_launch_ms < 50 && size.launch_pixels < pixels) size.launch_pixels = std::min(pixels, size.launch_pixels * 2);
  else if (slowest_launch_ms < 50 && size.pass_spp < 256) size.pass_spp *= 2;
  return size;
}

double estimated_rel_mse(const Film& film) {
  size_t n = film.mean.size();
  if (n == 0 || film.spp < 2) return 0;
  // With n_e even and n_o odd samples, Var(even - odd) = s^2 (1/n_e + 1/n_o) and Var(mean) = s^2 / n.
  double n_even = (film.spp + 1) / 2, n_odd = film.spp / 2;
  double scale = 1.0 / (film.spp * (1.0 / n_even + 1.0 / n_odd));
  double sum = 0;
  for (size_t i = 0; i < n; ++i) {
    double d = double(film.even_mean[i]) - film.odd_mean[i];
    double m = film.mean[i];
    sum += d * d * scale / (m * m + 0.01);
  }
  return sum / n;
}

RenderResult render(ClContext& cl, const DeviceScene& scene, const RenderOptions& options,
                    const PassObserver& observer) {
  RenderResult result;
  SceneHeader header = scene.header;
  header.max_depth = options.max_depth;
  header.seed = options.seed;
  header.rr_depth = options.rr_depth;
  header.sampler = options.sampler;
  header.spp = options.spp;
  const size_t pixels = size_t(header.width) * header.height;

  std::string build_options = kernel_options(options.all_features ? kFeatureAll : scene.features);
  if (options.debug_inject_hazards) build_options += " -DPC_DEBUG_INJECT_HAZARDS";
  KernelProgram program = build_kernel_program(cl, "integrator.cl", build_options);
  result.kernel_build_ms = program.build_ms;
  result.kernel_from_cache = program.from_cache;
  result.kernel_options = program.options;

  // Everything the render keeps on the device must fit in its memory.
  size_t scene_bytes = sizeof(SceneHeader) + scene.nodes.size() * sizeof(Bvh4Node) + scene.prims.size() * sizeof(Primitive) +
                       scene.shading.size() * sizeof(PrimShading) + scene.normals.size() * sizeof(pc_float4) +
                       scene.uvs.size() * sizeof(pc_float4) + scene.materials.size() * sizeof(Material) +
                       scene.lights.size() * sizeof(Light) + scene.light_cdf.size() * sizeof(float) +
                       scene.textures.size() * sizeof(Texture) + scene.texels.size() * sizeof(pc_float4) +
                       scene.env_dist.size() * sizeof(float);
  size_t film_bytes = pixels * (3 * sizeof(pc_float4) + sizeof(PassStats));
  if (scene_bytes + film_bytes > cl.info.global_memory)
    throw RuntimeFailure("the render needs " + std::to_string((scene_bytes + film_bytes) >> 20) + " MiB on the device (scene " +
                         std::to_string(scene_bytes >> 20) + " MiB, film " + std::to_string(film_bytes >> 20) + " MiB), " +
                         cl.info.name + " has " + std::to_string(cl.info.global_memory >> 20) + " MiB");

  auto start = std::chrono::steady_clock::now();
  ClBuffer header_buf(cl, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, sizeof header, &header);
  ClBuffer nodes = upload(cl, scene.nodes), prims = upload(cl, scene.prims), shading = upload(cl, scene.shading),
           normals = upload(cl, scene.normals), uvs = upload(cl, scene.uvs), materials = upload(cl, scene.materials),
           lights = upload(cl, scene.lights), cdf = upload(cl, scene.light_cdf), textures = upload(cl, scene.textures),
           texels = upload(cl, scene.texels), env_dist = upload(cl, scene.env_dist);
  ClBuffer film(cl, CL_MEM_READ_WRITE, 3 * pixels * sizeof(pc_float4));
  ClBuffer stats(cl, CL_MEM_WRITE_ONLY, pixels * sizeof(PassStats));
  uint32_t done = 0;
  if (options.resume) {
    if (options.resume->accumulators.size() != 3 * pixels)
      throw RuntimeFailure("the film to resume from has " + std::to_string(options.resume->accumulators.size() / 3) +
                           " pixels, the render " + std::to_string(pixels));
    CL_CHECK(clEnqueueWriteBuffer(cl.queue, film.mem, CL_TRUE, 0, 3 * pixels * sizeof(pc_float4),
                                  options.resume->accumulators.data(), 0, nullptr, nullptr));
    done = options.resume->spp;
  } else {
    const pc_float4 zero{0, 0, 0, 0};
    CL_CHECK(clEnqueueFillBuffer(cl.queue, film.mem, &zero, sizeof zero, 0, 3 * pixels * sizeof zero, 0, nullptr,
                                 nullptr));
  }

  ClKernel kernel(program.kernel("render_pass"));
  cl_mem args[] = {header_buf.mem, nodes.mem,    prims.mem,  shading.mem,  normals.mem,
                   uvs.mem,        materials.mem, lights.mem, cdf.mem,      textures.mem,
                   texels.mem,     env_dist.mem,  film.mem,   stats.mem};
  const cl_uint arg_count = sizeof args / sizeof args[0];
  for (cl_uint i = 0; i < arg_count; ++i) kernel.arg(i, args[i]);

  // Launch sizing. On a GPU, unless the caller fixed pass_spp, the samples and pixels per launch adapt
  // so that a launch takes 50-100 ms: long enough to amortise it, short enough that a desktop
  // watchdog never kills it. A CPU device has no watchdog, and PoCL compiles a new work-group function
  // for every new launch shape, so there a pass covers the whole film with about 2^20 samples. Any
  // sizing gives the same pixels.
  const bool adaptive = options.pass_spp == 0 && cl.info.is_gpu;
  uint32_t pass_spp = options.pass_spp;
  if (pass_spp == 0)
    pass_spp = adaptive || options.max_pass_seconds > 0 ? 1 : uint32_t(std::clamp<size_t>((size_t(1) << 20) / std::max<size_t>(pixels, 1), 1, 64));
  size_t launch_pixels = std::min(pixels, options.max_pixels_per_launch > 0 ? options.max_pixels_per_launch : pixels);
  std::vector<PassStats> pass_stats(pixels);
  std::optional<Film> last_film;
  auto seconds = [&] { return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(); };
  while (done < options.spp) {
    uint32_t count = std::min(pass_spp, options.spp - done);
    if (options.power_of_two_passes) {
      uint32_t next_power = 1;
      while (next_power <= done) next_power *= 2;
      count = std::min(count, next_power - done);
    }
    kernel.arg(arg_count, done);
    kernel.arg(arg_count + 1, count);
    double slowest_launch_ms = 0, pass_ms = 0;
    for (size_t first = 0; first < pixels; first += launch_pixels) {
      size_t n = std::min(launch_pixels, pixels - first);
      double ms = run_kernel(cl, kernel.k, n, options.work_group, first);
      result.kernel_ms += ms;
      pass_ms += ms;
      slowest_launch_ms = std::max(slowest_launch_ms, ms);
      result.launches++;
    }
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
    if (adaptive && count == pass_spp) {
      LaunchSize next = adapt_launch_size({pass_spp, launch_pixels}, slowest_launch_ms, pixels);
      pass_spp = next.pass_spp;
      launch_pixels = next.launch_pixels;
    }
    if (options.max_pass_seconds > 0 && count == pass_spp) {  // passes of about half to all of the limit
      if (pass_ms > 1e3 * options.max_pass_seconds && pass_spp > 1)
        pass_spp = std::max<uint32_t>(1, uint32_t(pass_spp * 1e3 * options.max_pass_seconds / pass_ms));
      else if (pass_ms < 0.5e3 * options.max_pass_seconds && pass_spp < 64)
        pass_spp *= 2;
    }
    // The observer may read the film several times in a pass (checkpoint, convergence log); it is read
    // from the device once, and the last pass's read is also the result.
    auto film_now = [&] {
      if (!last_film || last_film->spp != done) last_film = read_film(cl, film, header.width, header.height);
      return *last_film;
    };
    if (observer && !observer({done, options.spp, seconds(), result.kernel_build_ms}, film_now) && done < options.spp) {
      result.stopped_early = true;
      break;
    }
  }
  result.film = last_film && last_film->spp == done ? std::move(*last_film) : read_film(cl, film, header.width, header.height);
  result.render_seconds = seconds();
  return result;
}
