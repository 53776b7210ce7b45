// The pathcl command line: render, devices, info, rays, compare (apps/compare_command.cpp).
// Exit codes: 0 success, 2 bad usage or bad scene/mesh input, 1 runtime failure (device, kernel build, I/O).
#include <algorithm>
#include <csignal>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <optional>

#include <unistd.h>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "apps/bench_command.h"
#include "apps/compare_command.h"
#include "apps/convert_command.h"
#include "apps/denoise_command.h"
#include "runtime/checkpoint.h"
#include "runtime/denoise.h"
#include "runtime/device.h"
#include "runtime/errors.h"
#include "runtime/image_compare.h"
#include "runtime/atomic_file.h"
#include "runtime/image_io.h"
#include "runtime/interrupt.h"
#include "runtime/kernel_program.h"
#include "runtime/output_files.h"
#include "runtime/ranks.h"
#include "runtime/ray_trace.h"
#include "runtime/renderer.h"
#include "runtime/technique.h"
#include "scene/device_scene_build.h"
#include "scene/scene_error.h"
#include "scene/scene_import.h"
#include "scene/scene_limits.h"
#include "git_revision.h"

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

LoadedScene load(const std::string& path, const std::vector<std::string>& defines = {},
                 DeviceOrigin origin = DeviceOrigin::camera, uint32_t bvh_layouts = kBvhLayoutsAll) {
  LoadedScene s;
  auto start = std::chrono::steady_clock::now();
  s.description = load_scene(path, parse_scene_defines(defines));
  s.load_ms = ms_since(start);
  // Ray files are traced as one flat triangle list (and read so by other tracers): instances flattened.
  s.device = build_device_scene_taking_texels(s.description, origin,
                                              origin == DeviceOrigin::world ? Instancing::flatten : Instancing::keep,
                                              bvh_layouts);
  return s;
}

void write_json(const std::string& path, const nlohmann::json& j) { write_text_file(path, j.dump(2) + "\n"); }

// A count given on the command line, within the limits the scene file has for the same setting.
uint32_t count_option(const std::string& option, int64_t value, uint32_t lo, uint32_t hi) {
  if (value < int64_t(lo) || value > int64_t(hi))
    throw UsageError(option + " " + std::to_string(value) + ": expected an integer in [" + std::to_string(lo) + ", " +
                     std::to_string(hi) + "]");
  return uint32_t(value);
}

// A number of seconds or an error given on the command line: finite and > 0 (or >= 0).
double positive_option(const std::string& option, double value, bool allow_zero, const char* what) {
  if (!std::isfinite(value) || value < 0 || (!allow_zero && value == 0))
    throw UsageError(option + ": expected " + what);
  return value;
}

// The scene's figures; of the wide BVHs only the layouts built for the devices (DeviceScene::bvh_layouts).
nlohmann::json scene_stats(const LoadedScene& s) {
  const DeviceScene& d = s.device;
  nlohmann::json j = {{"triangles", d.triangle_count}, {"spheres", d.sphere_count},     {"lights", d.lights.size()},
                      {"bvh_nodes", d.bvh.node_count},  {"bvh_depth", d.bvh.depth},      {"bvh_leaves", d.bvh.leaf_count},
                      {"sah_cost", d.bvh.sah_cost},     {"bvh_build_ms", d.bvh.build_ms}, {"scene_load_ms", s.load_ms}};
  if (d.bvh_layouts & kBvhLayout4) j.update({{"bvh4_nodes", d.nodes.size()}, {"bvh4_depth", d.wide_depth}});
  if (d.bvh_layouts & kBvhLayout8) j.update({{"bvh8_nodes", d.wide8_nodes}, {"bvh8_depth", d.wide8_depth}});
  if (d.bvh_layouts & kBvhLayout16) j.update({{"bvh16_nodes", d.wide16_nodes}, {"bvh16_depth", d.wide16_depth}});
  return j;
}

// A progress bar on stderr: bar, samples per pixel done (on average over the film), samples per second,
// time left.
void print_progress(uint64_t done, uint64_t total, double seconds, size_t pixels) {
  const int width = 30;
  int filled = total > 0 ? int(double(done) / total * width) : width;
  double rate = seconds > 0 ? double(done) / seconds : 0;
  double eta = done > 0 ? seconds * (double(total) / done - 1) : 0;
  std::fprintf(stderr, "\r[%s%s] %.0f/%.0f spp  %.2f Msamples/s  ETA %.1f s ", std::string(filled, '#').c_str(),
               std::string(width - filled, '.').c_str(), double(done) / pixels, double(total) / pixels, rate * 1e-6, eta);
  if (done == total) std::fprintf(stderr, "\n");
}

struct RenderArgs {
  std::string scene, out, png, stats, device, sampler, integrator, reference, convergence, checkpoint, resume;
  std::vector<std::string> defines;  // -D NAME=VALUE: a Mitsuba scene's <default>s
  std::optional<std::string> aovs;
  double checkpoint_every = 60;
  double rank_timeout = 30;         // MPI: seconds beside a unit's expected time before a rank is lost
  bool coordinator_only = false;    // MPI: rank 0 renders on no device of its own
  RankJob::Faults rank_faults;      // MPI, tests: faults of the ranks other than 0
  std::optional<int64_t> spp, seed, max_depth;
  std::optional<double> time_budget, target_error;
  int64_t pass_spp = 0;
  size_t work_group = 0;
  uint32_t lanes = 0;
  bool quiet = false, all_features = false, variance = false, allow_mixed_devices = false, denoise = false;
};

// Rows of `--convergence`: one per power of two spp and at the end.
struct ConvergenceLog {
  std::string path;
  std::optional<Image> reference;
  std::string text = "wall_seconds,load_seconds,bvh_seconds,kernel_build_seconds,render_seconds,spp,rmse,relmse,mae,"
                     "mean,relmse_estimate\n";

  void add(double wall, const LoadedScene& s, double kernel_build_ms, double render_seconds, const Film& film) {
    char row[512];
    double mean = 0;
    for (float v : film.mean) mean += v;
    mean /= std::max<size_t>(film.mean.size(), 1);
    std::string errors = ",,";
    if (reference) {
      ImageErrors e = compare_images(*reference, film_image(film), nullptr);
      char buf[128];
      std::snprintf(buf, sizeof buf, "%.9g,%.9g,%.9g", e.rmse, e.rel_mse, e.mae);
      errors = buf;
    }
    std::snprintf(row, sizeof row, "%.6f,%.6f,%.6f,%.6f,%.6f,%u,%s,%.9g,%.9g\n", wall, s.load_ms * 1e-3,
                  s.device.bvh.build_ms * 1e-3, kernel_build_ms * 1e-3, render_seconds, film.spp, errors.c_str(), mean,
                  estimated_rel_mse(film));
    text += row;
  }

  static Image film_image(const Film& film) {
    Image image;
    image.width = film.width;
    image.height = film.height;
    image.rgb = film.mean;
    image.spp = int(film.spp);
    return image;
  }
};

// Clean-up that dropped geometry is worth a line: a mesh may not be what its author thinks it is. So is
// whatever loading changed or ignored (clamped texels, scaled MTL materials, unused MTL statements).
void warn_about_clean_up(const LoadedScene& s) {
  for (const std::string& w : s.description.warnings) std::fprintf(stderr, "warning: %s\n", w.c_str());
  std::vector<std::pair<std::string, CleanReport>> cleaned;
  for (const ShapeDesc& shape : s.description.shapes) cleaned.push_back({shape.label, shape.clean});
  for (const InstancedMesh& m : s.description.instanced_meshes) cleaned.push_back({m.label, m.clean});
  for (const auto& [label, c] : cleaned) {
    if (c.degenerate_faces + c.duplicate_faces > 0)
      std::fprintf(stderr, "warning: %s: removed %zu degenerate and %zu duplicate faces\n", label.c_str(),
                   c.degenerate_faces, c.duplicate_faces);
    if (c.self_intersecting)
      std::fprintf(stderr, "warning: %s: the closed mesh intersects itself; each connected part was oriented to a "
                   "positive volume instead of by CGAL's orient_to_bound_a_volume\n", label.c_str());
  }
  if (s.device.skipped_zero_area_emitters > 0)
    std::fprintf(stderr, "warning: %u zero-area emitters are not lights%s\n", s.device.skipped_zero_area_emitters,
                 s.device.lights.empty() ? ", and the scene has no other light: it renders black" : "");
}

// A device's name, with its rank's in an MPI render.
std::string device_name(const DeviceReport& d) {
  return d.rank == 0 ? d.name : d.name + " (rank " + std::to_string(d.rank) + ")";
}

// The names of the devices that rendered, joined.
std::string used_devices(const RenderResult& r) {
  std::string names;
  for (const DeviceReport& d : r.devices)
    if (d.used && d.units > 0) names += (names.empty() ? "" : ", ") + device_name(d);
  return names.empty() ? device_name(r.devices.front()) : names;
}

nlohmann::json device_stats(const RenderResult& r) {
  nlohmann::json list = nlohmann::json::array();
  for (const DeviceReport& d : r.devices)
    list.push_back({{"name", d.name},
                    {"platform", d.platform},
                    {"rank", d.rank},
                    {"host", d.host},
                    {"transfer_bytes", d.transfer_bytes},
                    {"class", d.arithmetic_class},
                    {"used", d.used},
                    {"note", d.note},
                    {"sub_device", d.sub_device},
                    {"compute_units", d.compute_units},
                    {"units", d.units},
                    {"samples", d.samples},
                    {"kernel_seconds", d.kernel_seconds},
                    {"transfer_seconds", d.transfer_seconds},
                    {"busy_seconds", d.busy_seconds},
                    {"idle_seconds", d.idle_seconds},
                    {"duplicates_run", d.duplicates_run},
                    {"duplicates_won", d.duplicates_won},
                    {"failures", d.failures},
                    {"kernel_build_ms", d.kernel_build_ms},
                    {"kernel_from_cache", d.kernel_from_cache},
                    {"kernel_private_bytes", d.kernel_private_bytes},
                    {"lanes", d.lanes},
                    {"unit_items", d.unit_items},
                    {"buffer_bytes", d.buffers},
                    {"probe_seconds", d.probe_seconds}});
  return list;
}

// An MPI render's ranks: each one's host, devices and what they did, summed over its devices.
nlohmann::json rank_stats(const RenderResult& r, int ranks, const std::vector<RankJob::LostRank>& lost) {
  nlohmann::json list = nlohmann::json::array();
  for (int k = 0; k < ranks; ++k) {
    nlohmann::json devices = nlohmann::json::array();
    uint64_t units = 0, samples = 0, bytes = 0;
    double transfer = 0, idle = 0, kernel = 0;
    std::string host;
    for (const DeviceReport& d : r.devices) {
      if (d.rank != uint32_t(k)) continue;
      devices.push_back(d.name);
      host = d.host;
      units += d.units;
      samples += d.samples;
      bytes += d.transfer_bytes;
      transfer += d.transfer_seconds;
      idle += d.idle_seconds;
      kernel += d.kernel_seconds;
    }
    bool is_lost = std::any_of(lost.begin(), lost.end(), [&](const RankJob::LostRank& l) { return l.rank == k; });
    list.push_back({{"rank", k}, {"host", k == 0 ? host_name() : host}, {"devices", devices},
                    {"units", units}, {"samples", samples}, {"kernel_seconds", kernel}, {"transfer_seconds", transfer},
                    {"transfer_bytes", bytes}, {"idle_seconds", idle}, {"lost", is_lost}});
  }
  return list;
}

// The merging integrators' settings (vcm, bpm, sppm; none for the others), for --stats and the EXR header:
// the first iteration's radius in scene units, its exponent and, where vcm merges, merging's factor in its
// MIS weights.
std::vector<std::pair<std::string, float>> merging_settings(const LightTransportHeader& lt) {
  if (!(lt.radius > 0)) return {};
  std::vector<std::pair<std::string, float>> s = {{"merging_radius", lt.radius}, {"merging_alpha", lt.alpha}};
  const uint32_t vcm = PC_VCM_CONNECT | PC_VCM_MERGE;
  if ((lt.vcm_mode & vcm) == vcm) s.push_back({"merging_mis", lt.merge_mis});
  return s;
}

// Device time of each named launch, in seconds.
nlohmann::json phase_stats(const RenderResult& r) {
  nlohmann::json j = nlohmann::json::object();
  for (const PhaseTime& p : r.phases) j[p.name] = p.ms * 1e-3;
  return j;
}

// The film's AOVs as EXR layers named as --aov takes them, channels by kind (AovInfo::channels); the
// header's "aovs" lists them, and with ids "shape_id_names" and "material_id_names" say what each id is: a
// JSON array of the shapes' labels ("shapes[3] (meshes/box.obj)") or the materials' names, id 1 first (0 is
// no hit).
void add_aov_layers(const Film& film, const SceneDescription& scene, Image& image) {
  std::string names;
  for (const Film::Aov& aov : film.aovs) {
    const AovInfo& info = aov_info(aov.aov);
    ImageLayer layer;
    layer.name = info.name;
    for (const char* c = info.channels; *c; ++c) layer.channels.push_back(std::string(1, *c));
    layer.values = aov.values;
    layer.integer = info.id;
    image.layers.push_back(std::move(layer));
    names += (names.empty() ? "" : ",") + std::string(info.name);
    if (aov.aov == PC_AOV_SHAPE_ID) {
      nlohmann::json shapes = nlohmann::json::array();
      for (const ShapeDesc& s : scene.shapes) shapes.push_back(s.label);
      image.attributes["shape_id_names"] = shapes.dump();
    }
    if (aov.aov == PC_AOV_MATERIAL_ID) {
      nlohmann::json materials = nlohmann::json::array();
      for (const MaterialDesc& m : scene.materials) materials.push_back(m.name);
      image.attributes["material_id_names"] = materials.dump();
    }
  }
  if (!names.empty()) image.attributes["aovs"] = names;
}

int run_render(const RenderArgs& a, RankJob& job) {
  auto started = std::chrono::steady_clock::now();
  // Everything the command line can get wrong is refused before the scene is loaded.
  RenderOptions opt;
  bool budgeted = a.time_budget || a.target_error;
  if (a.spp) opt.spp = count_option("--spp", *a.spp, 1, kMaxSpp);
  if (a.seed) opt.seed = count_option("--seed", *a.seed, 0, 0xffffffffu);
  if (a.max_depth) opt.max_depth = count_option("--max-depth", *a.max_depth, 0, kMaxDepth);
  opt.pass_spp = count_option("--pass-spp", a.pass_spp, 0, kMaxSpp);
  if (!a.sampler.empty() && !sampler_from_name(a.sampler, &opt.sampler))
    throw UsageError("--sampler " + a.sampler + ": expected independent, stratified, sobol or halton");
  bool integrator_given = !a.integrator.empty();
  if (integrator_given) opt.integrator = technique_named(a.integrator, "--integrator").name;
  if (a.aovs) opt.aovs = aov_mask_from_names(*a.aovs, "--aov");
  if (a.time_budget) opt.time_budget = positive_option("--time", *a.time_budget, false, "a finite number of seconds > 0");
  if (a.target_error) opt.target_error = positive_option("--target-error", *a.target_error, false, "a finite relMSE > 0");
  opt.checkpoint_every = positive_option("--checkpoint-every", a.checkpoint_every, true, "a finite number of seconds >= 0");
  std::string out = a.out.empty() ? std::filesystem::path(a.scene).stem().string() + ".exr" : a.out;
  if (a.variance && image_format("-o", out) != ImageFormat::exr)
    throw UsageError("--variance: the variance layer needs an EXR output, not -o " + out);
  if (a.aovs && opt.aovs != 0 && image_format("-o", out) != ImageFormat::exr)
    throw UsageError("--aov: the AOV layers need an EXR output, not -o " + out);
  if (a.denoise) {  // before the render: a missing library must not cost the render
    std::string why;
    if (!denoiser_available(&why)) throw RuntimeFailure("--denoise: " + why);
  }
  check_output_files({{"-o", out, true}, {"--png", a.png, true}, {"--stats", a.stats},
                      {"--convergence", a.convergence}, {"--checkpoint", a.checkpoint}});

  // The devices before the scene: it gets the BVH layouts they read and no others, or every layout where
  // other ranks render too (their devices are known only later).
  std::vector<DeviceInfo> devices;
  if (!a.coordinator_only) devices = select_devices(a.device);
  uint32_t layouts = job.size() > 1 || devices.empty() ? kBvhLayoutsAll : bvh_layouts(devices);
  LoadedScene s = load(a.scene, a.defines, DeviceOrigin::camera, layouts);
  warn_about_clean_up(s);
  // A time or error budget without --spp renders until the budget ends.
  if (!a.spp) opt.spp = budgeted ? kMaxSpp : s.description.render.spp;
  if (!a.seed) opt.seed = s.description.render.seed;
  if (!a.max_depth) opt.max_depth = s.description.render.max_depth;
  if (a.sampler.empty()) opt.sampler = s.description.render.sampler;
  const RenderSettings& rs = s.description.render;
  if (!integrator_given)
    opt.integrator = technique_named(rs.integrator, rs.integrator_place.empty() ? "render.integrator" : rs.integrator_place).name;
  if (!a.aovs)
    for (size_t i = 0; i < rs.aovs.size(); ++i) opt.aovs |= aov_mask_from_names(rs.aovs[i], rs.aov_places[i]);
  // The denoiser's guides (Open Image Denoise's albedo and normal), rendered beside the beauty.
  if (a.denoise) opt.aovs |= 1u << PC_AOV_ALBEDO | 1u << PC_AOV_NORMAL;
  opt.work_group = a.work_group;
  // The scene's options of its own technique; the command line's --lanes overrides.
  if (rs.integrator == opt.integrator)
    apply_technique_options(technique_named(opt.integrator, "render.integrator"), rs.integrator_options,
                            rs.integrator_place, opt);
  if (a.lanes != 0) opt.lanes = a.lanes;
  opt.all_features = a.all_features;
  opt.power_of_two_horizons = !a.convergence.empty();
  opt.allow_mixed_devices = a.allow_mixed_devices;
  ConvergenceLog log;
  log.path = a.convergence;
  if (!a.reference.empty()) {
    log.reference = read_exr(a.reference);
    if (log.reference->width != s.device.header.width || log.reference->height != s.device.header.height)
      throw UsageError(a.reference + ": the reference is " + std::to_string(log.reference->width) + "x" +
                       std::to_string(log.reference->height) + ", the render " +
                       std::to_string(s.device.header.width) + "x" + std::to_string(s.device.header.height));
  }

  opt.checkpoint = a.checkpoint;
  // The key hashes the scene's arrays byte by byte: a fifth of a second of one core for the 549k-triangle
  // benchmark terrain, so only a render that writes or reads a checkpoint pays for it.
  if (!a.checkpoint.empty() || !a.resume.empty()) opt.checkpoint_key = render_key(s.device, opt);
  Film resumed;
  if (!a.resume.empty()) {
    resumed = read_checkpoint(a.resume, s.device, opt);
    opt.resume = &resumed;
  }

  // This process's devices, then in an MPI render every other rank's.
  std::vector<WorkerSource> workers;
  if (!a.coordinator_only) workers = device_workers(devices);
  std::vector<std::string> rank_warnings;
  for (WorkerSource& w : job.remote_workers(a.rank_timeout, &rank_warnings)) workers.push_back(std::move(w));
  for (const std::string& w : rank_warnings) std::fprintf(stderr, "warning: %s\n", w.c_str());
  if (workers.empty())
    throw UsageError("--coordinator-only: no other rank has a device to render on (run under mpirun with more than one rank)");
  // Someone watches: stderr is a terminal, or under mpirun rank 0's stdout is (Open MPI gives rank 0 a terminal
  // for stdout only; its stderr reaches mpirun's terminal through a pipe, progress bar and all).
  bool show = !a.quiet && (isatty(STDERR_FILENO) || (job.size() > 1 && isatty(STDOUT_FILENO)));
  size_t pixels = size_t(s.device.header.width) * s.device.header.height;
  opt.interrupt = stop_signal();
  RenderCallbacks callbacks;
  if (show && !budgeted)
    callbacks.progress = [&](uint64_t done, uint64_t total, double seconds) { print_progress(done, total, seconds, pixels); };
  if (!log.path.empty())
    callbacks.horizon = [&](const Film& film, double seconds, double kernel_build_ms) {
      log.add(ms_since(started) * 1e-3, s, kernel_build_ms, seconds, film);
    };
  install_stop_handlers(out + " is not written; " +
                        (a.checkpoint.empty() ? std::string("the render is lost (--checkpoint keeps its state)")
                                              : "the checkpoint " + a.checkpoint + " holds the render as of its last save"));
  RenderResult r = render(workers, s.device, opt, callbacks);
  job.finish();
  const std::vector<RankJob::LostRank> lost = job.lost_ranks();
  for (const std::string& w : r.warnings) std::fprintf(stderr, "warning: %s\n", w.c_str());
  if (show && budgeted) std::fprintf(stderr, "stopped by %s after %u spp\n", r.stop_reason.c_str(), r.film.spp);
  if (!log.path.empty() && (r.film.spp & (r.film.spp - 1)) != 0)
    log.add(ms_since(started) * 1e-3, s, r.kernel_build_ms, r.render_seconds, r.film);

  Image image = ConvergenceLog::film_image(r.film);
  if (a.variance) image.variance = r.film.variance;
  image.attributes = {{"renderer", "pathcl"}, {"integrator", opt.integrator},
                      {"device", used_devices(r)}, {"seed", std::to_string(opt.seed)},
                      {"max_depth", std::to_string(opt.max_depth)}, {"sampler", sampler_name(opt.sampler)},
                      {"stop_reason", r.stop_reason}, {"determinism", r.determinism}};
  for (const auto& [key, value] : merging_settings(r.light)) image.attributes[key] = nlohmann::json(value).dump();
  add_aov_layers(r.film, s.description, image);
  double denoise_seconds = 0;
  if (a.denoise) {  // the beauty denoised, the raw one kept beside it (layer "raw")
    auto t = std::chrono::steady_clock::now();
    denoise_image(image, DenoiseOptions{});
    denoise_seconds = ms_since(t) * 1e-3;
  }
  write_image(out, image);
  if (!a.png.empty()) write_png(a.png, image);
  if (!log.path.empty()) write_text_file(log.path, log.text);
  const uint32_t rendered_spp = r.film.spp - (opt.resume ? opt.resume->spp : 0);
  double samples = double(pixels) * rendered_spp;
  if (!a.stats.empty()) {
    nlohmann::json j = scene_stats(s);
    j.update({{"device", used_devices(r)},
              {"platform", r.devices.front().platform},
              {"devices", device_stats(r)},
              {"determinism", r.determinism},
              {"width", r.film.width},
              {"height", r.film.height},
              {"spp", r.film.spp},
              {"seed", opt.seed},
              {"max_depth", opt.max_depth},
              {"sampler", sampler_name(opt.sampler)},
              {"integrator", opt.integrator},
              {"aovs", aov_names(opt.aovs)},
              {"phases", phase_stats(r)},
              {"denoise_seconds", denoise_seconds},
              {"lanes", r.devices.front().lanes},
              {"stop_reason", r.stop_reason},
              {"relmse_estimate", estimated_rel_mse(r.film)},
              {"kernel_build_ms", r.kernel_build_ms},
              {"kernel_from_cache", r.kernel_from_cache},
              {"kernel_options", r.kernel_options},
              {"setup_seconds", r.setup_seconds},
              {"render_seconds", r.render_seconds},
              {"kernel_seconds", r.kernel_ms * 1e-3},
              {"launches", r.launches},
              {"horizons", r.horizons},
              {"duplicate_checks", r.duplicate_checks},
              {"samples_per_second", samples / r.render_seconds},
              {"rays_traced", r.rays},
              {"rays_per_second", double(r.rays) / r.render_seconds},
              {"nan_samples", r.nan_samples},
              {"inf_samples", r.inf_samples},
              {"negative_samples", r.negative_samples},
              {"splat_overflows", r.splat_overflows}});
    if (job.size() > 1) {
      j["ranks"] = rank_stats(r, job.size(), lost);
      j["lost_ranks"] = lost.size();
    }
    for (const auto& [key, value] : merging_settings(r.light)) j[key] = value;
    if (r.light_vertices > 0) {  // bdpt and the merging integrators: light vertices kept, per iteration
      j["light_vertices"] = r.light_vertices;
      j["light_vertices_per_iteration"] = double(r.light_vertices) / std::max(rendered_spp, 1u);
    }
    write_json(a.stats, j);
  }
  if (!a.quiet)
    std::fprintf(stderr, "%s: %ux%u, %u spp in %.2f s (%.2f Msamples/s, %.2f Mrays/s) on %s -> %s\n", a.scene.c_str(),
                 r.film.width, r.film.height, r.film.spp, r.render_seconds, samples / r.render_seconds * 1e-6,
                 double(r.rays) / r.render_seconds * 1e-6, used_devices(r).c_str(), out.c_str());
  if (r.nan_samples + r.inf_samples + r.negative_samples > 0)
    std::fprintf(stderr, "warning: discarded %llu NaN, %llu infinite and %llu negative samples\n",
                 (unsigned long long)r.nan_samples, (unsigned long long)r.inf_samples,
                 (unsigned long long)r.negative_samples);
  if (r.splat_overflows > 0)
    std::fprintf(stderr, "warning: %llu fixed-point splat overflows (a bug: the splat scale is too fine for this scene)\n",
                 (unsigned long long)r.splat_overflows);
  if (!lost.empty()) {  // the image is whole and exact; the job script should still hear of the lost ranks
    for (const RankJob::LostRank& l : lost)
      std::fprintf(stderr, "error: lost %s; the other ranks rendered the whole image\n", l.why.c_str());
    std::fprintf(stderr, "error: lost_ranks = %zu\n", lost.size());
    return 1;
  }
  if (int signal = *stop_signal()) {
    std::fprintf(stderr, "interrupted after %u spp, wrote %s%s\n", r.film.spp, out.c_str(),
                 a.checkpoint.empty() ? "" : ("; resume with --resume " + a.checkpoint).c_str());
    return 128 + signal;
  }
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
    std::printf("[%zu] %s (%s)\n    platform: %s (%s)\n    compute units: %u, memory: %.1f GiB, %s, driver %s\n"
                "    float: %s divide and sqrt, denormals %s\n",
                i, d.name.c_str(), d.is_gpu ? "GPU" : "CPU", d.platform_name.c_str(), d.platform_version.c_str(),
                d.compute_units, double(d.global_memory) / (1u << 30), d.opencl_c_version.c_str(),
                d.driver_version.c_str(), d.correctly_rounded_divide_sqrt ? "correctly rounded" : "not correctly rounded",
                d.denormals ? "supported" : "may be flushed to zero");
  }
  return 0;
}

// The cleaned world-space triangles as OBJ, one object per shape named like the scene's JSON place
// ("o shapes[3]"), faces counter-clockwise = front, in the order that fixes `pathcl rays` primitive
// indices. A sphere is a comment line "# sphere shapes[i] CX CY CZ RADIUS FLIP" in world space. Other
// renderers and the peer benchmark's exporters (scripts/bench/) read this file to get the same geometry.
std::string cleaned_obj(const SceneDescription& d) {
  std::string text = "# pathcl info --dump-obj: cleaned world-space triangles of " + d.path + "\n";
  char line[160];
  size_t base = 1;
  for (size_t i = 0; i < d.shapes.size(); ++i) {
    const ShapeDesc shape = flattened_shape(d, d.shapes[i]);  // an instance as its placed copy
    if (shape.is_sphere) {
      std::snprintf(line, sizeof line, "# sphere shapes[%zu] %.9g %.9g %.9g %.9g %d\n", i, shape.center.x,
                    shape.center.y, shape.center.z, shape.radius, shape.flip_normals ? 1 : 0);
      text += line;
      continue;
    }
    text += "o shapes[" + std::to_string(i) + "]\n";
    for (const glm::dvec3& p : shape.mesh.positions) {
      std::snprintf(line, sizeof line, "v %.9g %.9g %.9g\n", p.x, p.y, p.z);
      text += line;
    }
    for (const auto& t : shape.mesh.triangles) {
      std::snprintf(line, sizeof line, "f %zu %zu %zu\n", base + t[0], base + t[1], base + t[2]);
      text += line;
    }
    base += shape.mesh.positions.size();
  }
  return text;
}

int run_info(const std::string& path, const std::vector<std::string>& defines, const std::string& dump_obj) {
  check_output_files({{"--dump-obj", dump_obj}});
  LoadedScene s = load(path, defines);
  if (!dump_obj.empty()) write_text_file(dump_obj, cleaned_obj(s.description));
  const SceneDescription& d = s.description;
  std::printf("scene: %s\ncamera: %ux%u, fov_y %.1f degrees\nmaterials: %zu\n", path.c_str(), d.camera.width,
              d.camera.height, d.camera.fov_y_degrees, d.materials.size());
  for (const std::string& w : d.warnings) std::printf("warning: %s\n", w.c_str());
  for (const ShapeDesc& shape : d.shapes) {
    if (shape.is_sphere) {
      std::printf("%s: sphere, radius %g%s\n", shape.label.c_str(), shape.radius,
                  shape_emits(shape) ? ", emitter" : "");
      continue;
    }
    if (shape.instance_of != PC_INVALID) {
      const InstancedMesh& m = d.instanced_meshes[shape.instance_of];
      std::printf("%s: instance of %s (%zu triangles)\n", shape.label.c_str(), m.label.c_str(), m.mesh.triangles.size());
      if (m.label != shape.label) continue;  // the clean-up below once, at the mesh's first placement
    }
    const TriangleMesh& mesh = shape.instance_of == PC_INVALID ? shape.mesh : d.instanced_meshes[shape.instance_of].mesh;
    const CleanReport& c = shape.instance_of == PC_INVALID ? shape.clean : d.instanced_meshes[shape.instance_of].clean;
    std::printf("%s: %zu vertices, %zu polygons in -> %zu vertices, %zu triangles out%s\n", shape.label.c_str(),
                c.input_vertices, c.input_polygons, mesh.positions.size(), mesh.triangles.size(),
                shape_emits(shape) ? ", emitter" : "");
    std::printf("    merged %zu duplicate vertices, removed %zu isolated vertices, %zu degenerate faces, %zu duplicate "
                "faces; triangulated %zu polygons into %zu triangles; flipped %zu faces; %s%s%s\n",
                c.merged_vertices, c.removed_isolated_vertices, c.degenerate_faces, c.duplicate_faces,
                c.polygons_triangulated, c.triangles_from_polygons, c.faces_flipped,
                c.self_intersecting ? "closed, self-intersecting" : c.closed ? "closed" : "open",
                mesh.normals.empty() ? "" : ", shading normals", mesh.colors.empty() ? "" : ", vertex colours");
  }
  const DeviceScene& v = s.device;
  size_t by_type[5] = {};
  for (const Light& l : v.lights) by_type[l.type]++;
  std::printf("primitives: %u triangles, %u spheres\n", v.triangle_count, v.sphere_count);
  if (v.instance_count > 0)
    std::printf("instances: %u placements of %zu meshes, %llu triangles placed\n", v.instance_count,
                d.instanced_meshes.size(), (unsigned long long)v.instanced_triangle_count);
  size_t groups = 0, grouped = 0;  // leaves of the light BVH with several lights (scene/light_bvh_build.h)
  for (const LightBvhNode& n : v.light_bvh)
    if (n.second == PC_INVALID && n.light_count > 1) groups++, grouped += n.light_count;
  std::printf("lights: %zu area (%u zero-area emitters skipped), %zu point, %zu spot, %zu directional, %zu environment; "
              "emitter groups: %zu (%zu lights)\n",
              by_type[PC_LIGHT_AREA], v.skipped_zero_area_emitters, by_type[PC_LIGHT_POINT], by_type[PC_LIGHT_SPOT],
              by_type[PC_LIGHT_DIRECTIONAL], by_type[PC_LIGHT_ENVIRONMENT], groups, grouped);
  std::printf("kernel options: %s\n", kernel_options(v.features).c_str());
  std::printf("bvh: %u nodes, %u leaves (at most %u primitives), depth %u, SAH cost %.2f, built in %.1f ms\n",
              v.bvh.node_count, v.bvh.leaf_count, v.bvh.max_leaf_size, v.bvh.depth, v.bvh.sah_cost, v.bvh.build_ms);
  std::printf("device bvh: 4-wide (GPUs) %zu nodes, depth %u; 8-wide (CPUs) %u nodes, depth %u; 16-wide (AVX-512 "
              "CPUs) %u nodes, depth %u\n",
              v.nodes.size(), v.wide_depth, v.wide8_nodes, v.wide8_depth, v.wide16_nodes, v.wide16_depth);
  std::printf("scene load and clean-up: %.1f ms\n", s.load_ms);
  return 0;
}

struct RaysArgs {
  std::string scene, rays, hits, device, stats;
  int64_t repeat = 5;
  size_t work_group = 0;
  uint32_t lanes = 1;
  bool any_hit = false;
};

int run_rays(const RaysArgs& a) {
  count_option("--repeat", a.repeat, 1, 1000000);
  check_output_files({{"--hits", a.hits}, {"--stats", a.stats}});
  std::vector<DeviceInfo> devices = select_devices(a.device);
  if (devices.size() > 1) throw UsageError("--device " + a.device + ": rays traces on one device, this selects " +
                                           std::to_string(devices.size()));
  // Ray files are in world coordinates; the scene gets the device's BVH layout only.
  LoadedScene s = load(a.scene, {}, DeviceOrigin::world, bvh_layouts(devices));
  std::vector<RayRecord> rays = read_ray_file(a.rays);
  ClContext cl(devices.front());
  TraceTiming timing;
  std::vector<HitRecord> hits = trace_ray_records(cl, s.device, rays, a.repeat, timing, a.work_group, a.lanes, a.any_hit);
  size_t hit_count = std::count_if(hits.begin(), hits.end(), [](const HitRecord& h) { return h.prim != PC_INVALID; });
  double kernel_ms = median(timing.kernel_ms), wall_ms = median(timing.wall_ms);
  double n = double(rays.size());
  std::printf("%s: %zu rays, %zu hits, median of %d: kernel %.2f ms (%.3f Mrays/s), wall %.2f ms (%.3f Mrays/s) on %s\n",
              a.rays.c_str(), rays.size(), hit_count, int(a.repeat), kernel_ms, n / kernel_ms * 1e-3, wall_ms,
              n / wall_ms * 1e-3, cl.info.name.c_str());
  if (!a.hits.empty()) write_hit_file(a.hits, hits);
  if (!a.stats.empty()) {
    nlohmann::json j = scene_stats(s);
    j.update({{"device", cl.info.name},
              {"rays", rays.size()},
              {"hits", hit_count},
              {"repeat", a.repeat},
              {"lanes", a.lanes},
              {"any_hit", a.any_hit},
              {"kernel_ms_median", kernel_ms},
              {"wall_ms_median", wall_ms},
              {"kernel_ms", timing.kernel_ms},
              {"wall_ms", timing.wall_ms},
              {"rays_per_second_kernel", n / kernel_ms * 1e3},
              {"rays_per_second_wall", n / wall_ms * 1e3},
              {"kernel_build_ms", timing.kernel_build_ms},
              {"kernel_from_cache", timing.kernel_from_cache}});
    write_json(a.stats, j);
  }
  return 0;
}

// `pathcl --version`: the version, the git revision built and the OpenCL platforms this machine has.
std::string version_text() {
  std::string text = std::string("pathcl ") + PATHCL_VERSION + " (git " + PATHCL_GIT_REVISION + ")\nOpenCL platforms:";
  std::vector<DeviceInfo> devices;
  try {
    devices = list_devices();
  } catch (const std::exception& e) {
    return text + " none (" + e.what() + ")";
  }
  if (devices.empty()) return text + " none (is an ICD such as pocl-opencl-icd installed?)";
  std::string last;
  for (const DeviceInfo& d : devices) {
    if (d.platform_name != last) text += "\n  " + d.platform_name + " (" + d.platform_version + "):";
    text += (d.platform_name == last ? ", " : " ") + d.name;
    last = d.platform_name;
  }
  return text;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"pathcl: a Monte-Carlo path tracer on OpenCL"};
  app.require_subcommand(1);
  app.set_version_flag("--version", version_text, "print the version, the git revision and the OpenCL platforms");

  RenderArgs ra;
  CLI::App* render_cmd = app.add_subcommand("render", "render a scene to EXR (and PNG)");
  render_cmd->add_option("scene", ra.scene, "scene file (JSON, Mitsuba XML or pbrt)")->required();
  render_cmd->add_option("-D,--define", ra.defines, "NAME=VALUE: a Mitsuba scene's <default> value, as Mitsuba's -D (repeatable)");
  render_cmd->add_option("-o,--output", ra.out, "output EXR (default: SCENE-NAME.exr)");
  render_cmd->add_option("--png", ra.png, "also write an sRGB PNG preview");
  render_cmd->add_option("--spp", ra.spp, "samples per pixel (overrides the scene)");
  render_cmd->add_option("--seed", ra.seed, "random seed (overrides the scene)");
  render_cmd->add_option("--max-depth", ra.max_depth, "largest number of scattering events (overrides the scene)");
  render_cmd->add_option("--device", ra.device,
                         "device index or name substring (see `pathcl devices`), cpu, gpu, a comma-separated list of "
                         "them, or all");
  render_cmd->add_flag("--allow-mixed-devices", ra.allow_mixed_devices,
                       "also render on devices whose arithmetic differs from the first device's (the image then "
                       "depends on the split)");
  render_cmd->add_option("--stats", ra.stats, "write statistics as JSON");
  render_cmd->add_option("--pass-spp", ra.pass_spp, "samples per pixel per kernel launch (0: adapt launches to 50-100 ms)");
  render_cmd->add_option("--work-group", ra.work_group,
                         "work-group size (0: 64, or 8 for 8 or 16 lanes; on CPU devices smaller for launches of few work items)");
  render_cmd->add_option("--lanes", ra.lanes,
                         "paths per work item of the path, light and bdpt integrators: 1, 8 or 16 (the same pixels); 0: the "
                         "device's "
                         "(16 or 8 on CPU devices, 1 on GPUs)");
  render_cmd->add_flag("--all-features", ra.all_features, "build the unspecialised kernel");
  render_cmd->add_option("--integrator", ra.integrator, technique_list() + " (default path; overrides the scene's render.integrator)");
  render_cmd->add_option("--aov", ra.aovs,
                         "also write these AOVs as EXR layers, a comma-separated list of albedo, normal, depth, position, "
                         "uv, shape_id, material_id (overrides the scene's render.aovs)");
  render_cmd->add_option("--sampler", ra.sampler, "independent, stratified, sobol or halton (overrides the scene)");
  render_cmd->add_option("--reference", ra.reference, "reference EXR for the error columns of --convergence");
  render_cmd->add_option("--convergence", ra.convergence, "write time, spp and error at every power of two spp (CSV)");
  render_cmd->add_option("--time", ra.time_budget, "stop after this many seconds of rendering");
  render_cmd->add_option("--target-error", ra.target_error, "stop when the estimated relMSE falls below this");
  render_cmd->add_flag("--variance", ra.variance, "add the per-pixel variance of the mean to the EXR");
  render_cmd->add_flag("--denoise", ra.denoise,
                       "denoise the image with Intel Open Image Denoise 2.x, guided by albedo and normal AOVs (rendered "
                       "for it); the raw beauty is kept as the EXR layer raw");
  render_cmd->add_option("--checkpoint", ra.checkpoint, "keep the render state in this file (atomically replaced)");
  render_cmd->add_option("--checkpoint-every", ra.checkpoint_every, "seconds between checkpoints (default 60)");
  render_cmd->add_option("--resume", ra.resume, "continue a render from a checkpoint of the same scene and settings");
  render_cmd->add_flag("-q,--quiet", ra.quiet, "no progress or summary on stderr");
  render_cmd->add_option("--rank-timeout", ra.rank_timeout,
                         "MPI (mpirun -np K pathcl render ...): seconds beyond a unit's expected time after which a rank "
                         "that has not answered is lost and its units go to the others (default 30)");
  render_cmd->add_flag("--coordinator-only", ra.coordinator_only,
                       "MPI: rank 0 coordinates and writes the output but renders on no device of its own");
  render_cmd->add_option("--debug-rank-delay", ra.rank_faults.unit_delay)->group("");
  render_cmd->add_option("--debug-rank-kill-after", ra.rank_faults.kill_after_units)->group("");
  render_cmd->add_flag("--debug-rank-corrupt", ra.rank_faults.corrupt_answers)->group("");
  render_cmd->add_flag("--debug-rank-perturb", ra.rank_faults.perturb)->group("");

  app.add_subcommand("devices", "list OpenCL platforms and devices");

  std::string info_scene;
  CLI::App* info_cmd = app.add_subcommand("info", "show what preprocessing did and the BVH, without rendering");
  info_cmd->add_option("scene", info_scene, "scene file (JSON, Mitsuba XML or pbrt)")->required();
  std::vector<std::string> info_defines;
  info_cmd->add_option("-D,--define", info_defines, "NAME=VALUE: a Mitsuba scene's <default> value (repeatable)");
  std::string info_dump_obj;
  info_cmd->add_option("--dump-obj", info_dump_obj, "write the cleaned world-space triangles as OBJ, one object per shape");

  RaysArgs ya;
  CLI::App* rays_cmd = app.add_subcommand("rays", "trace a ray file with the renderer's traversal and time it");
  rays_cmd->add_option("scene", ya.scene, "scene file (JSON, Mitsuba XML or pbrt)")->required();
  rays_cmd->add_option("--rays", ya.rays, "ray file: 32-byte records (origin, tmin, direction, tmax)")->required();
  rays_cmd->add_option("--hits", ya.hits, "write 16-byte hit records (t, primitive, u, v)");
  rays_cmd->add_option("--device", ya.device, "device index or name substring");
  rays_cmd->add_option("--repeat", ya.repeat, "timed repetitions (the median is reported)");
  rays_cmd->add_option("--stats", ya.stats, "write statistics as JSON");
  rays_cmd->add_option("--work-group", ya.work_group, "work-group size (0: 64, or 8 for 8 or 16 lanes)");
  rays_cmd->add_option("--lanes", ya.lanes, "rays per work item: 1, or packets of 8 or 16 (8- or 16-wide BVH devices)");
  rays_cmd->add_flag("--any-hit", ya.any_hit, "stop each ray at its first hit found (shadow rays; only hit or miss is defined)");

  add_compare_command(app);
  add_denoise_command(app);
  add_bench_command(app);
  add_convert_command(app);

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e);  // --help, --version
    std::fprintf(stderr, "error: %s (see --help)\n", e.what());
    return 2;
  }
  try {
    if (render_cmd->parsed()) {
      positive_option("--rank-timeout", ra.rank_timeout, false, "a finite number of seconds > 0");
      RankJob job(&argc, &argv);
      if (job.rank() > 0) return job.serve(ra.device, ra.rank_faults);
      return run_render(ra, job);
    }
    if (info_cmd->parsed()) return run_info(info_scene, info_defines, info_dump_obj);
    if (rays_cmd->parsed()) return run_rays(ya);
    if (compare_command_parsed()) return run_compare_command();
    if (denoise_command_parsed()) return run_denoise_command();
    if (convert_command_parsed()) return run_convert_command();
    if (bench_command_parsed()) return run_bench_command(std::string(PATHCL_VERSION) + " (git " + PATHCL_GIT_REVISION + ")");
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
