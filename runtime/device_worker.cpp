#include "runtime/device_worker.h"

#include <algorithm>
#include <chrono>
#include <thread>

#include "runtime/hash.h"

namespace {
bool has_extension(const DeviceInfo& d, const char* name) {
  size_t size = 0;
  CL_CHECK(clGetDeviceInfo(d.device, CL_DEVICE_EXTENSIONS, 0, nullptr, &size));
  std::string ext(size, '\0');
  CL_CHECK(clGetDeviceInfo(d.device, CL_DEVICE_EXTENSIONS, size, ext.data(), nullptr));
  return (" " + ext + " ").find(std::string(" ") + name + " ") != std::string::npos;
}
}  // namespace

DeviceWorker::DeviceWorker(const DeviceInfo& device)
    : owned_(std::make_unique<ClContext>(device)), cl_(owned_.get()) {}

DeviceWorker::DeviceWorker(ClContext& borrowed) : cl_(&borrowed) {}

void DeviceWorker::prepare(const DeviceScene& scene, const SceneHeader& header, const WorkerSettings& settings) {
  ClContext& cl = *cl_;
  fault_ = settings.fault;
  std::string options = settings.build_options;
  if (fault_.perturb) options += " -DPC_DEBUG_PERTURB";
  integrator_ = settings.integrator;
  // Only the integrator in use is built: the path kernel's program is the same with or without the others.
  if (light() && !settings.splat_pairs && has_extension(cl.info, "cl_khr_int64_base_atomics"))
    options += " -DPC_SPLAT_ATOMIC64";
  const bool bdpt = integrator_ == PC_INTEGRATOR_BDPT;
  if (bdpt) {
    options += " -DPC_BDPT_MAX_VERTICES=" + std::to_string(std::max<uint32_t>(settings.max_depth, 1));
  }
  if (settings.lanes != 0 && settings.lanes != 1 && settings.lanes != 8 && settings.lanes != 16)
    throw UsageError("--lanes " + std::to_string(settings.lanes) + ": one path per work item (1) or 8 or 16");
  if (settings.lanes > 1 && integrator_ != PC_INTEGRATOR_PATH)
    throw UsageError("--lanes " + std::to_string(settings.lanes) + ": only the path integrator runs over lanes yet");
  lanes_ = settings.lanes != 0 ? settings.lanes : integrator_ == PC_INTEGRATOR_PATH ? path_lanes(cl.info) : 1;
  if (lanes_ > 1) options += " -DPC_LANES=" + std::to_string(lanes_);  // the program's lane width (kernels/lanes.cl)
  program_.emplace(build_kernel_program(cl, bdpt ? "bdpt.cl" : light() ? "light_integrator.cl" : "integrator.cl", options));
  pixels_ = header.width * header.height;

  // Everything the render keeps on the device must fit in its memory.
  size_t scene_size = scene_bytes(scene, bvh_width(cl.info));
  size_t film_size = light() ? size_t(pixels_) * PC_SPLAT_WORDS * sizeof(uint64_t) : size_t(pixels_) * 3 * sizeof(pc_float4);
  if (scene_size + film_size > cl.info.global_memory)
    throw RuntimeFailure("the render needs " + std::to_string((scene_size + film_size) >> 20) +
                         " MiB on the device (scene " + std::to_string(scene_size >> 20) + " MiB, film " +
                         std::to_string(film_size >> 20) + " MiB), " + cl.info.name + " has " +
                         std::to_string(cl.info.global_memory >> 20) + " MiB");
  scene_ = std::make_unique<SceneBuffers>(cl, scene, header);
  film_ = ClBuffer(cl, CL_MEM_READ_WRITE, film_size);
  stats_ = ClBuffer(cl, CL_MEM_READ_WRITE, light() ? sizeof(SplatStats) : sizeof(UnitStats));
  std::string kernel_name = bdpt ? "bdpt_pass" : light() ? "light_pass" : "render_pass";
  kernel_ = std::make_unique<ClKernel>(program_->kernel(kernel_name.c_str()));
  first_unit_arg_ = scene_->bind(*kernel_);
  if (light()) {
    const LightTransportSetup& lt = *settings.light;
    light_header_ = ClBuffer(cl, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, sizeof lt.header, &lt.header);
    emission_cdf_ = ClBuffer(cl, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, lt.emission_cdf.size() * sizeof(float),
                             lt.emission_cdf.data());
    kernel_->arg(first_unit_arg_++, light_header_.mem);
    kernel_->arg(first_unit_arg_++, emission_cdf_.mem);
  }
  kernel_->arg(first_unit_arg_, film_.mem);
  kernel_->arg(first_unit_arg_ + 1, stats_.mem);

  work_group_ = kernel_work_group(cl, kernel_->k, settings.work_group, lanes_, "render");
  cl_ulong private_bytes = 0;
  CL_CHECK(clGetKernelWorkGroupInfo(kernel_->k, cl.info.device, CL_KERNEL_PRIVATE_MEM_SIZE, sizeof private_bytes,
                                    &private_bytes, nullptr));
  private_bytes_ = private_bytes;
  clear_film();
}

void DeviceWorker::clear_film() {
  const pc_float4 zero{0, 0, 0, 0};
  size_t bytes = light() ? size_t(pixels_) * PC_SPLAT_WORDS * sizeof(uint64_t) : size_t(pixels_) * 3 * sizeof zero;
  CL_CHECK(clEnqueueFillBuffer(cl_->queue, film_.mem, &zero, sizeof zero, 0, bytes, 0, nullptr, nullptr));
  CL_CHECK(clFinish(cl_->queue));
}

void DeviceWorker::read_splats() {
  splats_.resize(size_t(pixels_) * PC_SPLAT_WORDS);
  CL_CHECK(clEnqueueReadBuffer(cl_->queue, film_.mem, CL_TRUE, 0, splats_.size() * sizeof(uint64_t), splats_.data(), 0,
                               nullptr, nullptr));
}

double DeviceWorker::launch(uint32_t pixel_begin, uint32_t pixel_count, uint32_t pixel_stride, uint32_t sample_begin,
                            uint32_t sample_count) {
  const UnitStats zero{};
  CL_CHECK(clEnqueueWriteBuffer(cl_->queue, stats_.mem, CL_FALSE, 0, sizeof zero, &zero, 0, nullptr, nullptr));
  ClKernel& k = *kernel_;
  if (light()) {  // light_pass(..., path_begin, path_count, sample_begin, sample_count): paths are not strided
    static_assert(sizeof(SplatStats) == sizeof(UnitStats), "the stats buffer is cleared as UnitStats");
    k.arg(first_unit_arg_ + 2, cl_uint(pixel_begin));
    k.arg(first_unit_arg_ + 3, cl_uint(pixel_count));
    k.arg(first_unit_arg_ + 4, cl_uint(sample_begin));
    k.arg(first_unit_arg_ + 5, cl_uint(sample_count));
    return run_kernel(*cl_, k.k, pixel_count, work_group_);
  }
  k.arg(first_unit_arg_ + 2, cl_uint(pixel_begin));
  k.arg(first_unit_arg_ + 3, cl_uint(pixel_count));
  k.arg(first_unit_arg_ + 4, cl_uint(pixel_stride));
  k.arg(first_unit_arg_ + 5, cl_uint(sample_begin));
  k.arg(first_unit_arg_ + 6, cl_uint(sample_count));
  const uint32_t item_pixels = lanes_ > 1 ? lanes_ * PC_LANE_PIXELS : 1;  // kernels/integrator.cl, PC_ITEM_PIXELS
  return run_kernel(*cl_, k.k, (pixel_count + item_pixels - 1) / item_pixels, work_group_);
}

uint64_t DeviceWorker::probe(uint32_t count, uint32_t spp) {
  count = std::min(count, pixels_);
  if (light()) {  // light paths [0, count): their splats, wherever they land, and the counts
    launch(0, count, 1, 0, spp);
    read_splats();
    SplatStats stats{};
    CL_CHECK(clEnqueueReadBuffer(cl_->queue, stats_.mem, CL_TRUE, 0, sizeof stats, &stats, 0, nullptr, nullptr));
    clear_film();
    return fnv1a(&stats, sizeof stats, fnv1a(splats_.data(), splats_.size() * sizeof(uint64_t)));
  }
  uint32_t stride = pixels_ / count;
  launch(0, count, stride, 0, spp);
  // The probe's pixels lie `stride` apart in the film: one rectangular read gathers them.
  std::vector<pc_float4> acc(3 * size_t(count));
  const size_t pixel_bytes = 3 * sizeof(pc_float4);
  const size_t origin[3] = {0, 0, 0}, region[3] = {pixel_bytes, count, 1};
  CL_CHECK(clEnqueueReadBufferRect(cl_->queue, film_.mem, CL_TRUE, origin, origin, region, stride * pixel_bytes, 0,
                                   pixel_bytes, 0, acc.data(), 0, nullptr, nullptr));
  UnitStats stats{};
  CL_CHECK(clEnqueueReadBuffer(cl_->queue, stats_.mem, CL_TRUE, 0, sizeof stats, &stats, 0, nullptr, nullptr));
  clear_film();
  uint64_t h = fnv1a(acc.data(), acc.size() * sizeof(pc_float4));
  return fnv1a(&stats, sizeof stats, h);
}

UnitOutput DeviceWorker::run(const WorkUnit& u, const std::vector<pc_float4>* input) {
  auto start = std::chrono::steady_clock::now();
  if (fault_.delay_seconds > 0) std::this_thread::sleep_for(std::chrono::duration<double>(fault_.delay_seconds));
  if (fault_.fail_after_units >= 0 && units_run_ >= uint64_t(fault_.fail_after_units))
    throw RuntimeFailure(cl_->info.name + ": test failure after " + std::to_string(units_run_) + " units");
  ++units_run_;
  UnitOutput out;
  if (light()) {  // from a cleared splat film: the unit's splats alone, added into the render's on the host
    clear_film();
    out.kernel_ms = launch(u.pixel_begin, u.pixel_count, 1, u.sample_begin, u.sample_count);
    read_splats();
    SplatStats s{};
    CL_CHECK(clEnqueueReadBuffer(cl_->queue, stats_.mem, CL_TRUE, 0, sizeof s, &s, 0, nullptr, nullptr));
    out.stats.rays_lo = s.rays_lo;
    out.stats.rays_hi = s.rays_hi;
    out.stats.nan_samples = s.nan_splats;
    out.stats.inf_samples = s.inf_splats;
    out.stats.negative_samples = s.negative_splats;
    out.splat_overflows = s.overflows;
    out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return out;
  }
  const size_t offset = size_t(u.pixel_begin) * 3 * sizeof(pc_float4), bytes = size_t(u.pixel_count) * 3 * sizeof(pc_float4);
  if (input)
    CL_CHECK(clEnqueueWriteBuffer(cl_->queue, film_.mem, CL_FALSE, offset, bytes, input->data(), 0, nullptr, nullptr));
  out.kernel_ms = launch(u.pixel_begin, u.pixel_count, 1, u.sample_begin, u.sample_count);
  result_.resize(3 * size_t(u.pixel_count));
  CL_CHECK(clEnqueueReadBuffer(cl_->queue, film_.mem, CL_FALSE, offset, bytes, result_.data(), 0, nullptr, nullptr));
  CL_CHECK(clEnqueueReadBuffer(cl_->queue, stats_.mem, CL_TRUE, 0, sizeof out.stats, &out.stats, 0, nullptr, nullptr));
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return out;
}
