#include "runtime/device_worker.h"

#include <algorithm>
#include <chrono>
#include <thread>

#include "runtime/hash.h"
#include "runtime/technique.h"

DeviceWorker::DeviceWorker(const DeviceInfo& device)
    : owned_(std::make_unique<ClContext>(device)), cl_(owned_.get()) {}

DeviceWorker::DeviceWorker(ClContext& borrowed) : cl_(&borrowed) {}

void DeviceWorker::prepare(const DeviceScene& scene, const SceneHeader& header, const WorkerSettings& settings) {
  ClContext& cl = *cl_;
  const Technique& t = *settings.technique;
  technique_ = &t;
  layout_ = settings.layout;
  fault_ = settings.fault;
  lanes_ = !t.lanes ? 1 : settings.lanes != 0 ? settings.lanes : path_lanes(cl.info);
  work_group_chosen_ = settings.work_group > 0;
  std::string options = settings.build_options;
  if (fault_.perturb) options += " -DPC_DEBUG_PERTURB";
  TechniqueBuild build{&cl.info, lanes_, settings.max_depth, settings.splat_pairs};
  // Only the technique in use is built: its program is the same with or without the others.
  if (t.build_options) options += t.build_options(build);
  program_.emplace(build_kernel_program(cl, t.kernel_file, options));
  const bool aovs = layout_.layers.size() > t.layers.size();
  // The AOV pass runs over the device's lanes whatever the technique does (the same bits at every width).
  const uint32_t aov_lanes = settings.lanes != 0 ? settings.lanes : path_lanes(cl.info);
  if (aovs)
    aov_program_.emplace(build_kernel_program(
        cl, "aov.cl", settings.build_options + (aov_lanes > 1 ? " -DPC_LANES=" + std::to_string(aov_lanes) : "")));

  // Everything the render keeps on the device must fit in its memory.
  size_t scene_size = scene_bytes(scene, bvh_width(cl.info));
  size_t film_size = layout_.total_words() * sizeof(uint32_t);
  if (scene_size + film_size > cl.info.global_memory)
    throw RuntimeFailure("the render needs " + std::to_string((scene_size + film_size) >> 20) +
                         " MiB on the device (scene " + std::to_string(scene_size >> 20) + " MiB, film " +
                         std::to_string(film_size >> 20) + " MiB), " + cl.info.name + " has " +
                         std::to_string(cl.info.global_memory >> 20) + " MiB");
  scene_ = std::make_unique<SceneBuffers>(cl, scene, header);
  film_ = ClBuffer(cl, CL_MEM_READ_WRITE, film_size);
  stats_ = ClBuffer(cl, CL_MEM_READ_WRITE, sizeof(UnitStats));

  const bool emission = uses_emission(t);
  if (emission) {
    const LightTransportSetup& lt = *settings.light;
    light_header_ = ClBuffer(cl, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, sizeof lt.header, &lt.header);
    emission_cdf_ = upload(cl, lt.emission_cdf);
  }
  TechniqueSizes sizes{layout_.pixels, settings.max_depth, 0, &cl.info,
                       settings.light ? settings.light->header.light_paths : 0, header.prim_count,
                       settings.light ? settings.light->header.bootstrap : 0};
  sizes.unit_items = unit_items_ = technique_unit_items(t, sizes);
  for (const TechniqueBuffer& b : t.buffers) {
    const cl_uint zero = 0;
    size_t bytes = std::max<size_t>(b.bytes(sizes), sizeof zero);
    bytes = (bytes + sizeof zero - 1) / sizeof zero * sizeof zero;
    buffer_bytes_[b.name] = bytes;
    ClBuffer& buffer = technique_buffers_.emplace_back(cl, CL_MEM_READ_WRITE, bytes);
    CL_CHECK(clEnqueueFillBuffer(cl.queue, buffer.mem, &zero, sizeof zero, 0, bytes, 0, nullptr, nullptr));
  }
  // The technique's phases: (PC_SCENE_PARAMS, then their arguments by name; TechniquePhase).
  for (const TechniquePhase& tp : t.phases) {
    Phase p;
    p.name = tp.name;
    p.kernel = std::make_unique<ClKernel>(program_->kernel(tp.entry.c_str()));
    cl_uint arg = scene_->bind(*p.kernel);
    for (const std::string& name : tp.args) {
      const ClBuffer* buffer = name == "film" ? &film_ : name == "stats" ? &stats_ : nullptr;
      if (name == "lt") buffer = &light_header_;
      if (name == "emission_cdf") buffer = &emission_cdf_;
      for (size_t i = 0; i < t.buffers.size(); ++i)
        if (t.buffers[i].name == name) buffer = &technique_buffers_[i];
      if (name == "unit") {
        p.first_unit_arg = arg;
        arg += t.units == UnitKind::pixels ? 5 : 4;
      } else if (buffer) {
        p.kernel->arg(arg++, buffer->mem);
      } else {
        throw std::logic_error("technique " + t.name + ", phase " + tp.name + ": no argument called " + name);
      }
    }
    p.strided = t.units == UnitKind::pixels;
    p.item_pixels = lanes_ > 1 ? lanes_ * PC_LANE_PIXELS : 1;  // kernels/integrator.cl, PC_ITEM_PIXELS
    p.items = tp.items;
    p.work_group = kernel_work_group(cl, p.kernel->k, settings.work_group, lanes_, tp.name);
    cl_ulong private_bytes = 0;
    CL_CHECK(clGetKernelWorkGroupInfo(p.kernel->k, cl.info.device, CL_KERNEL_PRIVATE_MEM_SIZE, sizeof private_bytes,
                                      &private_bytes, nullptr));
    private_bytes_ = std::max<uint64_t>(private_bytes_, private_bytes);
    phases_.push_back(std::move(p));
  }

  if (aovs) {  // kernels/aov.cl: (PC_SCENE_PARAMS, aov header, shape tables, film, unit range), a pixel a lane
    Phase aov;
    aov.name = "aov";
    aov.kernel = std::make_unique<ClKernel>(aov_program_->kernel("aov_pass"));
    cl_uint arg = scene_->bind(*aov.kernel);
    aov_header_ = ClBuffer(cl, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, sizeof settings.aov, &settings.aov);
    prim_shapes_ = upload(cl, scene.prim_shapes);
    instance_shapes_ = upload(cl, scene.instance_shapes);
    aov.kernel->arg(arg++, aov_header_.mem);
    aov.kernel->arg(arg++, prim_shapes_.mem);
    aov.kernel->arg(arg++, instance_shapes_.mem);
    aov.kernel->arg(arg++, film_.mem);
    aov.first_unit_arg = arg;
    aov.item_pixels = aov_lanes;
    aov.work_group = kernel_work_group(cl, aov.kernel->k, settings.work_group, aov_lanes, "aov");
    phases_.push_back(std::move(aov));
  }
  first_launches();
  clear_film();
}

WorkerReport DeviceWorker::report() const {
  WorkerReport r;
  r.kernel_build_ms = program_->build_ms + (aov_program_ ? aov_program_->build_ms : 0) + first_launch_ms_;
  r.kernel_from_cache = program_->from_cache && (!aov_program_ || aov_program_->from_cache);
  r.kernel_options = program_->options;
  r.kernel_private_bytes = private_bytes_;
  r.lanes = lanes_;
  r.unit_items = unit_items_;
  r.buffers = buffer_bytes_;
  return r;
}

void DeviceWorker::clear_film() {
  const cl_uint zero = 0;
  CL_CHECK(clEnqueueFillBuffer(cl_->queue, film_.mem, &zero, sizeof zero, 0, layout_.total_words() * sizeof zero, 0,
                               nullptr, nullptr));
  CL_CHECK(clFinish(cl_->queue));
}

void DeviceWorker::clear_commutative_layers() {
  const cl_uint zero = 0;
  for_each_unit_part(layout_, PC_LAYER_COMMUTATIVE, 0, 0, [&](const FilmLayout::UnitPart& p) {
    CL_CHECK(clEnqueueFillBuffer(cl_->queue, film_.mem, &zero, sizeof zero, p.film_offset * sizeof zero,
                                 p.words * sizeof zero, 0, nullptr, nullptr));
  });
}

void DeviceWorker::read_commutative_layers(std::vector<uint32_t>& out) {
  out.resize(layout_.words_per_pixel(PC_LAYER_COMMUTATIVE) * layout_.pixels);
  for_each_unit_part(layout_, PC_LAYER_COMMUTATIVE, 0, 0, [&](const FilmLayout::UnitPart& p) {
    CL_CHECK(clEnqueueReadBuffer(cl_->queue, film_.mem, CL_FALSE, p.film_offset * sizeof(uint32_t),
                                 p.words * sizeof(uint32_t), out.data() + p.payload_offset, 0, nullptr, nullptr));
  });
}

void DeviceWorker::set_unit_args(Phase& p, uint32_t pixel_begin, uint32_t pixel_count, uint32_t pixel_stride,
                                 uint32_t sample_begin, uint32_t sample_count) {
  cl_uint a = p.first_unit_arg;
  p.kernel->arg(a++, cl_uint(pixel_begin));
  p.kernel->arg(a++, cl_uint(pixel_count));
  if (p.strided) p.kernel->arg(a++, cl_uint(pixel_stride));
  p.kernel->arg(a++, cl_uint(sample_begin));
  p.kernel->arg(a++, cl_uint(sample_count));
}

void DeviceWorker::first_launches() {
  auto start = std::chrono::steady_clock::now();
  for (Phase& p : phases_) {
    set_unit_args(p, 0, 0, 1, 0, 0);
    run_kernel(*cl_, p.kernel->k, std::max<size_t>(p.work_group, 1), p.work_group);
  }
  first_launch_ms_ = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

void DeviceWorker::launch(uint32_t pixel_begin, uint32_t pixel_count, uint32_t pixel_stride, uint32_t sample_begin,
                          uint32_t sample_count, UnitOutput* out) {
  const UnitStats zero{};
  CL_CHECK(clEnqueueWriteBuffer(cl_->queue, stats_.mem, CL_FALSE, 0, sizeof zero, &zero, 0, nullptr, nullptr));
  // Per-sample techniques run their phases once per sample, in order (Technique::per_sample). The launches
  // go to the in-order queue one after another, and the host waits for the last one only.
  const bool per_sample = technique_->per_sample;
  std::vector<std::pair<size_t, ClEvent>> launched;  // (phase, event)
  for (uint32_t s = sample_begin; s < sample_begin + sample_count; s += per_sample ? 1 : sample_count) {
    for (size_t i = 0; i < phases_.size(); ++i) {
      Phase& p = phases_[i];
      set_unit_args(p, pixel_begin, pixel_count, pixel_stride, s, per_sample ? 1 : sample_count);
      const size_t items =
          p.items ? p.items(pixel_count, layout_.pixels, p.item_pixels) : (pixel_count + p.item_pixels - 1) / p.item_pixels;
      if (items > 0)
        launched.emplace_back(
            i, enqueue_kernel(*cl_, p.kernel->k, items, launch_work_group(cl_->info, p.work_group, work_group_chosen_, items)));
    }
  }
  if (!launched.empty()) CL_CHECK(clWaitForEvents(1, &launched.back().second.event));
  if (out && sample_count > 0)
    while (out->phases.size() < phases_.size()) out->phases.push_back({phases_[out->phases.size()].name, 0.0});
  for (const auto& [i, event] : launched) {
    const double ms = kernel_event_ms(event);
    if (out) {
      out->kernel_ms += ms;
      out->phases[i].ms += ms;
    }
  }
}

uint64_t DeviceWorker::probe(uint32_t count, uint32_t spp) {
  count = std::min({count, layout_.pixels, unit_items_});
  // Light paths are not strided: the probe's paths are [0, count).
  uint32_t stride = technique_->units == UnitKind::pixels ? layout_.pixels / count : 1;
  launch(0, count, stride, 0, spp, nullptr);
  // Each ordered layer's probe pixels lie `stride` apart in its plane: one rectangular read gathers them.
  uint64_t h = fnv1a(nullptr, 0);
  for (size_t i = 0; i < layout_.layers.size(); ++i) {
    if (layout_.layers[i].kind != PC_LAYER_ORDERED) continue;
    const size_t pixel_bytes = layout_.layers[i].words * sizeof(uint32_t);
    std::vector<uint32_t> words(size_t(layout_.layers[i].words) * count);
    const size_t origin[3] = {layout_.offset(i) * sizeof(uint32_t), 0, 0}, host[3] = {0, 0, 0},
                 region[3] = {pixel_bytes, count, 1};
    CL_CHECK(clEnqueueReadBufferRect(cl_->queue, film_.mem, CL_TRUE, origin, host, region, stride * pixel_bytes, 0,
                                     pixel_bytes, 0, words.data(), 0, nullptr, nullptr));
    h = fnv1a(words.data(), words.size() * sizeof(uint32_t), h);
  }
  std::vector<uint32_t> commutative;
  read_commutative_layers(commutative);
  UnitStats stats{};
  CL_CHECK(clEnqueueReadBuffer(cl_->queue, stats_.mem, CL_TRUE, 0, sizeof stats, &stats, 0, nullptr, nullptr));
  clear_film();
  h = fnv1a(commutative.data(), commutative.size() * sizeof(uint32_t), h);
  return fnv1a(&stats, sizeof stats, h);
}

UnitOutput DeviceWorker::run(const WorkUnit& u, const std::vector<uint32_t>* input) {
  auto start = std::chrono::steady_clock::now();
  if (fault_.delay_seconds > 0) std::this_thread::sleep_for(std::chrono::duration<double>(fault_.delay_seconds));
  if (fault_.fail_after_units >= 0 && units_run_ >= uint64_t(fault_.fail_after_units))
    throw RuntimeFailure(cl_->info.name + ": test failure after " + std::to_string(units_run_) + " units");
  ++units_run_;
  UnitOutput out;
  // Commutative layers from cleared sums: the unit's splats alone, added into the render's on the host.
  clear_commutative_layers();
  // Ordered layers: the unit's pixels, uploaded where the device's copy is not at the unit's first sample,
  // and read back after the launches, layer after layer.
  if (input)
    for_each_unit_part(layout_, PC_LAYER_ORDERED, u.pixel_begin, u.pixel_count, [&](const FilmLayout::UnitPart& p) {
      CL_CHECK(clEnqueueWriteBuffer(cl_->queue, film_.mem, CL_FALSE, p.film_offset * sizeof(uint32_t),
                                    p.words * sizeof(uint32_t), input->data() + p.payload_offset, 0, nullptr, nullptr));
    });
  launch(u.pixel_begin, u.pixel_count, 1, u.sample_begin, u.sample_count, &out);
  out.ordered.resize(layout_.words_per_pixel(PC_LAYER_ORDERED) * u.pixel_count);
  for_each_unit_part(layout_, PC_LAYER_ORDERED, u.pixel_begin, u.pixel_count, [&](const FilmLayout::UnitPart& p) {
    CL_CHECK(clEnqueueReadBuffer(cl_->queue, film_.mem, CL_FALSE, p.film_offset * sizeof(uint32_t),
                                 p.words * sizeof(uint32_t), out.ordered.data() + p.payload_offset, 0, nullptr, nullptr));
  });
  read_commutative_layers(out.commutative);
  UnitStats s{};
  CL_CHECK(clEnqueueReadBuffer(cl_->queue, stats_.mem, CL_TRUE, 0, sizeof s, &s, 0, nullptr, nullptr));
  // The splat kernels' SplatStats has the same first words; its overflows and light vertices are UnitStats's
  // pad[0] and pad[1].
  static_assert(sizeof(SplatStats) == sizeof(UnitStats) && offsetof(SplatStats, overflows) == offsetof(UnitStats, pad) &&
                    offsetof(SplatStats, light_vertices) == offsetof(UnitStats, pad) + sizeof(pc_uint),
                "SplatStats reads as UnitStats");
  out.stats = s;
  out.splat_overflows = s.pad[0];
  out.light_vertices = s.pad[1];
  out.stats.pad[0] = out.stats.pad[1] = 0;
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return out;
}
