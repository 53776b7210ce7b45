// The pathcl command line: render, devices, info, rays.
// Exit codes: 0 success, 2 bad usage or bad scene/mesh input, 1 runtime failure (device, kernel build, I/O).
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <optional>

#include <unistd.h>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "runtime/device.h"
#include "runtime/errors.h"
#include "runtime/image_io.h"
#include "runtime/ray_trace.h"
#include "runtime/renderer.h"
#include "scene/device_scene.h"
#include "scene/scene_error.h"

namespace {

double ms_since(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t).count();
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  size_t n = v.size();
  return n == 0 ? 0 : n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

struct LoadedScene {
  SceneDescription description;
  DeviceScene device;
  double load_ms = 0;  // reading, mesh loading and cleaning
};

LoadedScene load(const std::string& path) {
  LoadedScene s;
  auto start = std::chrono::steady_clock::now();
  s.description = load_scene(path);
  s.load_ms = ms_since(start);
  s.device = build_device_scene(s.description);
  return s;
}

// Writes a JSON file through a temporary file and a rename.
void write_json(const std::string& path, const nlohmann::json& j) {
  std::string tmp = path + ".partial";
  {
    std::ofstream out(tmp);
    if (!(out << j.dump(2) << "\n")) throw RuntimeFailure(path + ": cannot write");
  }
  std::filesystem::rename(tmp, path);
}

void make_parent_directory(const std::string& path) {
  std::filesystem::path parent = std::filesystem::path(path).parent_path();
  std::error_code ec;
  if (!parent.empty()) std::filesystem::create_directories(parent, ec);
}

nlohmann::json scene_stats(const LoadedScene& s) {
  const DeviceScene& d = s.device;
  return {{"triangles", d.triangle_count},     {"spheres", d.sphere_count},        {"lights", d.lights.size()},
          {"bvh_nodes", d.nodes.size()},        {"bvh_depth", d.bvh.depth},         {"bvh_leaves", d.bvh.leaf_count},
          {"sah_cost", d.bvh.sah_cost},         {"bvh_build_ms", d.bvh.build_ms},   {"scene_load_ms", s.load_ms}};
}

// A progress bar on stderr: bar, samples per pixel done, samples per second, time left.
void print_progress(uint32_t done, uint32_t total, double seconds, size_t pixels) {
  const int width = 30;
  int filled = int(double(done) / total * width);
  double rate = seconds > 0 ? double(done) * pixels / seconds : 0;
  double eta = done > 0 ? seconds * (double(total) / done - 1) : 0;
  std::fprintf(stderr, "\r[%s%s] %u/%u spp  %.2f Msamples/s  ETA %.1f s ", std::string(filled, '#').c_str(),
               std::string(width - filled, '.').c_str(), done, total, rate * 1e-6, eta);
  if (done == total) std::fprintf(stderr, "\n");
}

struct RenderArgs {
  std::string scene, out, png, stats, device;
  std::optional<uint32_t> spp, seed, max_depth;
  uint32_t pass_spp = 0;
  size_t work_group = 0;
  bool quiet = false, all_features = false;
};

int run_render(const RenderArgs& a) {
  LoadedScene s = load(a.scene);
  RenderOptions opt;
  opt.spp = a.spp.value_or(s.description.render.spp);
  opt.seed = a.seed.value_or(s.description.render.seed);
  opt.max_depth = a.max_depth.value_or(s.description.render.max_depth);
  opt.pass_spp = a.pass_spp;
  opt.work_group = a.work_group;
  opt.all_features = a.all_features;
  if (opt.spp == 0) throw UsageError("--spp: expected at least 1 sample per pixel");
  std::string out = a.out.empty() ? std::filesystem::path(a.scene).stem().string() + ".exr" : a.out;

  ClContext cl(select_device(a.device));
  bool show = !a.quiet && isatty(STDERR_FILENO);
  size_t pixels = size_t(s.device.header.width) * s.device.header.height;
  RenderResult r = render(cl, s.device, opt, [&](uint32_t done, uint32_t total, double seconds) {
    if (show) print_progress(done, total, seconds, pixels);
  });

  Image image;
  image.width = r.width;
  image.height = r.height;
  image.rgb = std::move(r.rgb);
  image.spp = int(r.spp);
  image.attributes = {{"renderer", "pathcl"}, {"device", cl.info.name}, {"seed", std::to_string(opt.seed)},
                      {"max_depth", std::to_string(opt.max_depth)}};
  make_parent_directory(out);
  write_exr(out, image);
  if (!a.png.empty()) {
    make_parent_directory(a.png);
    write_png(a.png, image);
  }
  double samples = double(pixels) * r.spp;
  if (!a.stats.empty()) {
    nlohmann::json j = scene_stats(s);
    j.update({{"device", cl.info.name},
              {"platform", cl.info.platform_name},
              {"width", r.width},
              {"height", r.height},
              {"spp", r.spp},
              {"seed", opt.seed},
              {"max_depth", opt.max_depth},
              {"kernel_build_ms", r.kernel_build_ms},
              {"kernel_from_cache", r.kernel_from_cache},
              {"kernel_options", r.kernel_options},
              {"render_seconds", r.render_seconds},
              {"kernel_seconds", r.kernel_ms * 1e-3},
              {"passes", r.passes},
              {"samples_per_second", samples / r.render_seconds},
              {"rays_traced", r.rays},
              {"rays_per_second", double(r.rays) / r.render_seconds},
              {"nan_samples", r.nan_samples},
              {"inf_samples", r.inf_samples},
              {"negative_samples", r.negative_samples}});
    make_parent_directory(a.stats);
    write_json(a.stats, j);
  }
  if (!a.quiet)
    std::fprintf(stderr, "%s: %ux%u, %u spp in %.2f s (%.2f Msamples/s, %.2f Mrays/s) on %s -> %s\n", a.scene.c_str(),
                 r.width, r.height, r.spp, r.render_seconds, samples / r.render_seconds * 1e-6,
                 double(r.rays) / r.render_seconds * 1e-6, cl.info.name.c_str(), out.c_str());
  if (r.nan_samples + r.inf_samples + r.negative_samples > 0)
    std::fprintf(stderr, "warning: discarded %llu NaN, %llu infinite and %llu negative samples\n",
                 (unsigned long long)r.nan_samples, (unsigned long long)r.inf_samples,
                 (unsigned long long)r.negative_samples);
  return 0;
}

int run_devices() {
  std::vector<DeviceInfo> devices = list_devices();
  if (devices.empty()) {
    std::printf("no OpenCL devices\n");
    return 1;
  }
  for (size_t i = 0; i < devices.size(); ++i) {
    const DeviceInfo& d = devices[i];
    std::printf("[%zu] %s (%s)\n    platform: %s (%s)\n    compute units: %u, memory: %.1f GiB, %s, driver %s\n", i,
                d.name.c_str(), d.is_gpu ? "GPU" : "CPU", d.platform_name.c_str(), d.platform_version.c_str(),
                d.compute_units, double(d.global_memory) / (1u << 30), d.opencl_c_version.c_str(),
                d.driver_version.c_str());
  }
  return 0;
}

int run_info(const std::string& path) {
  LoadedScene s = load(path);
  const SceneDescription& d = s.description;
  std::printf("scene: %s\ncamera: %ux%u, fov_y %.1f degrees\nmaterials: %zu\n", path.c_str(), d.camera.width,
              d.camera.height, d.camera.fov_y_degrees, d.materials.size());
  for (const ShapeDesc& shape : d.shapes) {
    if (shape.is_sphere) {
      std::printf("%s: sphere, radius %g%s\n", shape.label.c_str(), shape.radius,
                  shape.emission != glm::vec3(0) ? ", emitter" : "");
      continue;
    }
    const CleanReport& c = shape.clean;
    std::printf("%s: %zu vertices, %zu polygons in -> %zu vertices, %zu triangles out%s\n", shape.label.c_str(),
                c.input_vertices, c.input_polygons, shape.mesh.positions.size(), shape.mesh.triangles.size(),
                shape.emission != glm::vec3(0) ? ", emitter" : "");
    std::printf("    merged %zu duplicate vertices, removed %zu isolated vertices, %zu degenerate faces, %zu duplicate "
                "faces; triangulated %zu polygons into %zu triangles; flipped %zu faces; %s%s\n",
                c.merged_vertices, c.removed_isolated_vertices, c.degenerate_faces, c.duplicate_faces,
                c.polygons_triangulated, c.triangles_from_polygons, c.faces_flipped, c.closed ? "closed" : "open",
                shape.mesh.normals.empty() ? "" : ", smooth normals");
  }
  const DeviceScene& v = s.device;
  std::printf("primitives: %u triangles, %u spheres\nlights: %zu area lights (%u zero-area emitters skipped)\n",
              v.triangle_count, v.sphere_count, v.lights.size(), v.skipped_zero_area_emitters);
  std::printf("bvh: %zu nodes, %u leaves (at most %u primitives), depth %u, SAH cost %.2f, built in %.1f ms\n",
              v.nodes.size(), v.bvh.leaf_count, v.bvh.max_leaf_size, v.bvh.depth, v.bvh.sah_cost, v.bvh.build_ms);
  std::printf("scene load and clean-up: %.1f ms\n", s.load_ms);
  return 0;
}

struct RaysArgs {
  std::string scene, rays, hits, device, stats;
  int repeat = 5;
  size_t work_group = 0;
};

int run_rays(const RaysArgs& a) {
  LoadedScene s = load(a.scene);
  std::vector<RayRecord> rays = read_ray_file(a.rays);
  if (a.repeat < 1) throw UsageError("--repeat: expected at least 1");
  ClContext cl(select_device(a.device));
  TraceTiming timing;
  std::vector<HitRecord> hits = trace_ray_records(cl, s.device, rays, a.repeat, timing, a.work_group);
  size_t hit_count = std::count_if(hits.begin(), hits.end(), [](const HitRecord& h) { return h.prim != PC_INVALID; });
  double kernel_ms = median(timing.kernel_ms), wall_ms = median(timing.wall_ms);
  double n = double(rays.size());
  std::printf("%s: %zu rays, %zu hits, median of %d: kernel %.2f ms (%.3f Mrays/s), wall %.2f ms (%.3f Mrays/s) on %s\n",
              a.rays.c_str(), rays.size(), hit_count, a.repeat, kernel_ms, n / kernel_ms * 1e-3, wall_ms,
              n / wall_ms * 1e-3, cl.info.name.c_str());
  if (!a.hits.empty()) {
    make_parent_directory(a.hits);
    write_hit_file(a.hits, hits);
  }
  if (!a.stats.empty()) {
    nlohmann::json j = scene_stats(s);
    j.update({{"device", cl.info.name},
              {"rays", rays.size()},
              {"hits", hit_count},
              {"repeat", a.repeat},
              {"kernel_ms_median", kernel_ms},
              {"wall_ms_median", wall_ms},
              {"kernel_ms", timing.kernel_ms},
              {"wall_ms", timing.wall_ms},
              {"rays_per_second_kernel", n / kernel_ms * 1e3},
              {"rays_per_second_wall", n / wall_ms * 1e3},
              {"kernel_build_ms", timing.kernel_build_ms},
              {"kernel_from_cache", timing.kernel_from_cache}});
    make_parent_directory(a.stats);
    write_json(a.stats, j);
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"pathcl: a Monte-Carlo path tracer on OpenCL"};
  app.require_subcommand(1);

  RenderArgs ra;
  CLI::App* render_cmd = app.add_subcommand("render", "render a scene to EXR (and PNG)");
  render_cmd->add_option("scene", ra.scene, "scene file (JSON)")->required();
  render_cmd->add_option("-o,--output", ra.out, "output EXR (default: SCENE-NAME.exr)");
  render_cmd->add_option("--png", ra.png, "also write an sRGB PNG preview");
  render_cmd->add_option("--spp", ra.spp, "samples per pixel (overrides the scene)");
  render_cmd->add_option("--seed", ra.seed, "random seed (overrides the scene)");
  render_cmd->add_option("--max-depth", ra.max_depth, "largest number of scattering events (overrides the scene)");
  render_cmd->add_option("--device", ra.device, "device index or name substring (see `pathcl devices`)");
  render_cmd->add_option("--stats", ra.stats, "write statistics as JSON");
  render_cmd->add_option("--pass-spp", ra.pass_spp, "samples per pixel per kernel launch (0: automatic)");
  render_cmd->add_option("--work-group", ra.work_group, "work-group size (0: the driver's choice)");
  render_cmd->add_flag("--all-features", ra.all_features, "build the unspecialised kernel");
  render_cmd->add_flag("-q,--quiet", ra.quiet, "no progress or summary on stderr");

  app.add_subcommand("devices", "list OpenCL platforms and devices");

  std::string info_scene;
  CLI::App* info_cmd = app.add_subcommand("info", "show what preprocessing did and the BVH, without rendering");
  info_cmd->add_option("scene", info_scene, "scene file (JSON)")->required();

  RaysArgs ya;
  CLI::App* rays_cmd = app.add_subcommand("rays", "trace a ray file with the renderer's traversal and time it");
  rays_cmd->add_option("scene", ya.scene, "scene file (JSON)")->required();
  rays_cmd->add_option("--rays", ya.rays, "ray file: 32-byte records (origin, tmin, direction, tmax)")->required();
  rays_cmd->add_option("--hits", ya.hits, "write 16-byte hit records (t, primitive, u, v)");
  rays_cmd->add_option("--device", ya.device, "device index or name substring");
  rays_cmd->add_option("--repeat", ya.repeat, "timed repetitions (the median is reported)");
  rays_cmd->add_option("--stats", ya.stats, "write statistics as JSON");
  rays_cmd->add_option("--work-group", ya.work_group, "work-group size (0: the driver's choice)");

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    int code = app.exit(e);
    return code == 0 ? 0 : 2;
  }
  try {
    if (render_cmd->parsed()) return run_render(ra);
    if (info_cmd->parsed()) return run_info(info_scene);
    if (rays_cmd->parsed()) return run_rays(ya);
    return run_devices();
  } catch (const SceneError& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 2;
  } catch (const UsageError& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
}
