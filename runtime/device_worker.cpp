#include "runtime/device_worker.h"

#include <algorithm>
#include <chrono>
#include <thread>

#include "runtime/hash.h"

DeviceWorker::DeviceWorker(const DeviceInfo& device)
    : owned_(std::make_unique<ClContext>(device)), cl_(owned_.get()) {}

DeviceWorker::DeviceWorker(ClContext& borrowed) : cl_(&borrowed) {}

void DeviceWorker::prepare(const DeviceScene& scene, const SceneHeader& header, const WorkerSettings& settings) {
  ClContext& cl = *cl_;
  fault_ = settings.fault;
  std::string options = settings.build_options;
  if (fault_.perturb) options += " -DPC_DEBUG_PERTURB";
  program_.emplace(build_kernel_program(cl, "integrator.cl", options));
  pixels_ = header.width * header.height;

  // Everything the render keeps on the device must fit in its memory.
  size_t scene_size = scene_bytes(scene, bvh_width(cl.info)), film_size = size_t(pixels_) * 3 * sizeof(pc_float4);
  if (scene_size + film_size > cl.info.global_memory)
    throw RuntimeFailure("the render needs " + std::to_string((scene_size + film_size) >> 20) +
                         " MiB on the device (scene " + std::to_string(scene_size >> 20) + " MiB, film " +
                         std::to_string(film_size >> 20) + " MiB), " + cl.info.name + " has " +
                         std::to_string(cl.info.global_memory >> 20) + " MiB");
  scene_ = std::make_unique<SceneBuffers>(cl, scene, header);
  film_ = ClBuffer(cl, CL_MEM_READ_WRITE, film_size);
  stats_ = ClBuffer(cl, CL_MEM_READ_WRITE, sizeof(UnitStats));
  kernel_ = std::make_unique<ClKernel>(program_->kernel("render_pass"));
  first_unit_arg_ = scene_->bind(*kernel_);
  kernel_->arg(first_unit_arg_, film_.mem);
  kernel_->arg(first_unit_arg_ + 1, stats_.mem);

  // One work-group size for every launch: PoCL compiles a work-group function for each new local size,
  // and chooses the local size from the global size when it is left to it.
  size_t limit = 0;
  CL_CHECK(clGetKernelWorkGroupInfo(kernel_->k, cl.info.device, CL_KERNEL_WORK_GROUP_SIZE, sizeof limit, &limit, nullptr));
  if (settings.work_group > limit)
    throw UsageError("--work-group " + std::to_string(settings.work_group) + ": " + cl.info.name +
                     " runs the render kernel in work groups of at most " + std::to_string(limit));
  work_group_ = settings.work_group > 0 ? settings.work_group : std::min<size_t>(64, limit);
  clear_film();
}

void DeviceWorker::clear_film() {
  const pc_float4 zero{0, 0, 0, 0};
  CL_CHECK(clEnqueueFillBuffer(cl_->queue, film_.mem, &zero, sizeof zero, 0, size_t(pixels_) * 3 * sizeof zero, 0,
                               nullptr, nullptr));
  CL_CHECK(clFinish(cl_->queue));
}

double DeviceWorker::launch(uint32_t pixel_begin, uint32_t pixel_count, uint32_t pixel_stride, uint32_t sample_begin,
                            uint32_t sample_count) {
  const UnitStats zero{};
  CL_CHECK(clEnqueueWriteBuffer(cl_->queue, stats_.mem, CL_FALSE, 0, sizeof zero, &zero, 0, nullptr, nullptr));
  ClKernel& k = *kernel_;
  k.arg(first_unit_arg_ + 2, cl_uint(pixel_begin));
  k.arg(first_unit_arg_ + 3, cl_uint(pixel_count));
  k.arg(first_unit_arg_ + 4, cl_uint(pixel_stride));
  k.arg(first_unit_arg_ + 5, cl_uint(sample_begin));
  k.arg(first_unit_arg_ + 6, cl_uint(sample_count));
  return run_kernel(*cl_, k.k, pixel_count, work_group_);
}

uint64_t DeviceWorker::probe(uint32_t count, uint32_t spp) {
  count = std::min(count, pixels_);
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
