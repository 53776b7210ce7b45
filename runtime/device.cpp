#include "runtime/device.h"

#include <algorithm>
#include <cctype>
#include <cstdlib>

#include "scene/device_scene.h"

namespace {

std::string platform_string(cl_platform_id p, cl_platform_info what) {
  size_t size = 0;
  CL_CHECK(clGetPlatformInfo(p, what, 0, nullptr, &size));
  std::string s(size, '\0');
  CL_CHECK(clGetPlatformInfo(p, what, size, s.data(), nullptr));
  while (!s.empty() && s.back() == '\0') s.pop_back();
  return s;
}

std::string device_string(cl_device_id d, cl_device_info what) {
  size_t size = 0;
  CL_CHECK(clGetDeviceInfo(d, what, 0, nullptr, &size));
  std::string s(size, '\0');
  CL_CHECK(clGetDeviceInfo(d, what, size, s.data(), nullptr));
  while (!s.empty() && s.back() == '\0') s.pop_back();
  return s;
}

template <class T>
T device_value(cl_device_id d, cl_device_info what) {
  T value{};
  CL_CHECK(clGetDeviceInfo(d, what, sizeof(T), &value, nullptr));
  return value;
}

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  return s;
}

}  // namespace

std::vector<DeviceInfo> list_devices() {
  // PoCL's CPU devices compile a kernel's work-group function again for every local size, for a global offset
  // other than zero and for grids of 65535 items or more ("specialization"). pathcl's kernels trace a whole
  // path or more per work item, where the specialized functions are no faster (docs/benchmarks-notes.md:
  // samples/s and rays/s the same within noise), so one generic function per kernel serves every launch: a
  // 512 x 512 bdpt render compiled its kernel twice (the start-up launches are narrow), the tests once per
  // work-group size. Set before the first OpenCL call, where the user has not set it.
  setenv("POCL_WORK_GROUP_SPECIALIZATION", "0", 0);
  cl_uint platform_count = 0;
  cl_int status = clGetPlatformIDs(0, nullptr, &platform_count);
  if (status == CL_PLATFORM_NOT_FOUND_KHR || platform_count == 0) return {};
  CL_CHECK(status);
  std::vector<cl_platform_id> platforms(platform_count);
  CL_CHECK(clGetPlatformIDs(platform_count, platforms.data(), nullptr));
  std::vector<DeviceInfo> devices;
  for (cl_platform_id p : platforms) {
    cl_uint count = 0;
    if (clGetDeviceIDs(p, CL_DEVICE_TYPE_ALL, 0, nullptr, &count) != CL_SUCCESS || count == 0) continue;
    std::vector<cl_device_id> ids(count);
    CL_CHECK(clGetDeviceIDs(p, CL_DEVICE_TYPE_ALL, count, ids.data(), nullptr));
    for (cl_device_id d : ids) {
      DeviceInfo info;
      info.platform = p;
      info.device = d;
      info.platform_name = platform_string(p, CL_PLATFORM_NAME);
      info.platform_version = platform_string(p, CL_PLATFORM_VERSION);
      info.name = device_string(d, CL_DEVICE_NAME);
      info.version = device_string(d, CL_DEVICE_VERSION);
      info.driver_version = device_string(d, CL_DRIVER_VERSION);
      info.opencl_c_version = device_string(d, CL_DEVICE_OPENCL_C_VERSION);
      cl_device_type type = device_value<cl_device_type>(d, CL_DEVICE_TYPE);
      info.is_gpu = (type & CL_DEVICE_TYPE_GPU) != 0;
      info.is_cpu = (type & CL_DEVICE_TYPE_CPU) != 0;
      info.compute_units = device_value<cl_uint>(d, CL_DEVICE_MAX_COMPUTE_UNITS);
      info.global_memory = device_value<cl_ulong>(d, CL_DEVICE_GLOBAL_MEM_SIZE);
      info.max_alloc = device_value<cl_ulong>(d, CL_DEVICE_MAX_MEM_ALLOC_SIZE);
      info.max_work_group = device_value<size_t>(d, CL_DEVICE_MAX_WORK_GROUP_SIZE);
      cl_device_fp_config fp = device_value<cl_device_fp_config>(d, CL_DEVICE_SINGLE_FP_CONFIG);
      info.correctly_rounded_divide_sqrt = (fp & CL_FP_CORRECTLY_ROUNDED_DIVIDE_SQRT) != 0;
      info.denormals = (fp & CL_FP_DENORM) != 0;
      info.preferred_float_width = device_value<cl_uint>(d, CL_DEVICE_PREFERRED_VECTOR_WIDTH_FLOAT);
      info.index = devices.size();
      devices.push_back(info);
    }
  }
  return devices;
}

bool is_oclgrind(const DeviceInfo& device) { return lower(device.platform_name).find("oclgrind") != std::string::npos; }
bool is_pocl(const DeviceInfo& device) { return device.platform_name == "Portable Computing Language"; }

uint32_t bvh_width(const DeviceInfo& device) {
  if (const char* forced = std::getenv("PATHCL_BVH_WIDTH")) {
    if (std::string(forced) == "4") return 4;
    if (std::string(forced) == "8") return 8;
    if (std::string(forced) == "16") return 16;
    throw UsageError(std::string("PATHCL_BVH_WIDTH=") + forced + ": expected 4, 8 or 16");
  }
  if (!device.is_cpu) return 4;
  return device.preferred_float_width >= 16 ? 16 : 8;
}

uint32_t bvh_layout(uint32_t width) { return width == 16 ? kBvhLayout16 : width == 8 ? kBvhLayout8 : kBvhLayout4; }

uint32_t bvh_layouts(const std::vector<DeviceInfo>& devices) {
  uint32_t layouts = 0;
  for (const DeviceInfo& d : devices) layouts |= bvh_layout(bvh_width(d));
  return layouts;
}

uint32_t path_lanes(const DeviceInfo& device) {
  if (const char* forced = std::getenv("PATHCL_LANES")) {
    for (uint32_t lanes : {1u, 8u, 16u})
      if (std::string(forced) == std::to_string(lanes)) return lanes;
    throw UsageError(std::string("PATHCL_LANES=") + forced + ": expected 1, 8 or 16");
  }
  if (!device.is_cpu || is_oclgrind(device)) return 1;
  return device.preferred_float_width >= 16 ? 16 : 8;
}

DeviceInfo select_device(const std::string& selector) {
  std::vector<DeviceInfo> devices = list_devices();
  if (devices.empty())
    throw RuntimeFailure("no OpenCL device found (is an ICD such as pocl-opencl-icd installed?)");
  if (selector.empty()) {
    auto usable = [](const DeviceInfo& d) { return !is_oclgrind(d); };
    for (const DeviceInfo& d : devices)
      if (d.is_gpu && usable(d)) return d;
    for (const DeviceInfo& d : devices)
      if (d.is_cpu && usable(d)) return d;
    for (const DeviceInfo& d : devices)
      if (usable(d)) return d;
    throw RuntimeFailure("the only OpenCL device is Oclgrind, which is never the default: name it with --device");
  }
  if (std::all_of(selector.begin(), selector.end(), [](unsigned char c) { return std::isdigit(c); })) {
    size_t index = std::stoul(selector);
    if (index < devices.size()) return devices[index];
    throw UsageError("--device " + selector + ": no device with that index (" + std::to_string(devices.size()) +
                     " found; see `pathcl devices`)");
  }
  for (const DeviceInfo& d : devices)
    if (lower(d.name).find(lower(selector)) != std::string::npos ||
        lower(d.platform_name).find(lower(selector)) != std::string::npos)
      return d;
  throw UsageError("--device " + selector + ": no device or platform name contains it (see `pathcl devices`)");
}

namespace {

std::vector<DeviceInfo> select_by_type_or_name(const std::string& selector) {
  std::string type = lower(selector);
  if (type != "cpu" && type != "gpu") return {select_device(selector)};
  std::vector<DeviceInfo> of_type;
  for (const DeviceInfo& d : list_devices())
    if ((type == "gpu" ? d.is_gpu : d.is_cpu) && !is_oclgrind(d) && (type == "gpu" || of_type.empty()))
      of_type.push_back(d);
  if (of_type.empty())
    throw UsageError("--device " + selector + ": no " + (type == "gpu" ? "GPU" : "CPU") +
                     " device found (see `pathcl devices`)");
  return of_type;
}

}  // namespace

std::vector<DeviceInfo> select_devices(const std::string& selectors) {
  if (selectors.empty()) return {select_device("")};
  std::vector<DeviceInfo> chosen;
  if (lower(selectors) == "all") {
    chosen = list_devices();
    if (chosen.empty()) throw RuntimeFailure("no OpenCL device found (is an ICD such as pocl-opencl-icd installed?)");
    return chosen;
  }
  size_t start = 0;
  while (start <= selectors.size()) {
    size_t comma = selectors.find(',', start);
    std::string one = selectors.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
    if (one.empty()) throw UsageError("--device " + selectors + ": an empty selector in the list");
    for (const DeviceInfo& d : select_by_type_or_name(one)) {
      for (const DeviceInfo& c : chosen)
        if (c.index == d.index)
          throw UsageError("--device " + selectors + ": \"" + one + "\" selects device " + std::to_string(d.index) +
                           " (" + d.name + ") a second time");
      chosen.push_back(d);
    }
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  return chosen;
}

DeviceInfo partition_device(const DeviceInfo& device, cl_uint units) {
  if (units == 0 || units >= device.compute_units) return device;
  cl_device_partition_property props[] = {CL_DEVICE_PARTITION_BY_COUNTS, cl_device_partition_property(units),
                                          CL_DEVICE_PARTITION_BY_COUNTS_LIST_END, 0};
  cl_device_id sub = nullptr;
  cl_uint count = 0;
  if (clCreateSubDevices(device.device, props, 1, &sub, &count) != CL_SUCCESS || count != 1) return device;
  DeviceInfo info = device;
  info.device = sub;
  info.compute_units = units;
  info.sub_device = true;
  return info;
}

ClContext::ClContext(const DeviceInfo& device) : info(device) {
  cl_context_properties props[] = {CL_CONTEXT_PLATFORM, cl_context_properties(device.platform), 0};
  context = CL_CHECKED(clCreateContext, props, 1, &info.device, nullptr, nullptr);
  queue = CL_CHECKED(clCreateCommandQueue, context, info.device, CL_QUEUE_PROFILING_ENABLE);
}

ClContext::~ClContext() {
  for (const auto& kept : kept_programs) clReleaseProgram(kept.second);
  if (queue) clReleaseCommandQueue(queue);
  if (context) clReleaseContext(context);
  if (info.sub_device) clReleaseDevice(info.device);
}

ClBuffer::ClBuffer(ClContext& cl, cl_mem_flags flags, size_t bytes, const void* host) {
  // Checked here, with the sizes in the message, rather than left to a driver that may fail late or
  // vaguely (CL_OUT_OF_RESOURCES at the first launch) or not at all until the launch crashes.
  if (bytes > cl.info.max_alloc || bytes > cl.info.global_memory)
    throw RuntimeFailure("a buffer of " + std::to_string(bytes >> 20) + " MiB exceeds what " + cl.info.name +
                         " allows in one allocation (" + std::to_string(cl.info.max_alloc >> 20) + " MiB of " +
                         std::to_string(cl.info.global_memory >> 20) + " MiB): the scene or film is too large");
  mem = CL_CHECKED(clCreateBuffer, cl.context, flags, bytes, const_cast<void*>(host));
}

ClBuffer::~ClBuffer() {
  if (mem) clReleaseMemObject(mem);
}

ClBuffer& ClBuffer::operator=(ClBuffer&& o) noexcept {
  if (this != &o) {
    if (mem) clReleaseMemObject(mem);
    mem = o.mem;
    o.mem = nullptr;
  }
  return *this;
}

size_t kernel_work_group(const ClContext& cl, cl_kernel kernel, size_t requested, uint32_t lanes, const std::string& what) {
  size_t limit = 0;
  CL_CHECK(clGetKernelWorkGroupInfo(kernel, cl.info.device, CL_KERNEL_WORK_GROUP_SIZE, sizeof limit, &limit, nullptr));
  if (requested > limit)
    throw UsageError("--work-group " + std::to_string(requested) + ": " + cl.info.name + " runs the " + what +
                     " kernel in work groups of at most " + std::to_string(limit));
  return requested > 0 ? requested : std::min<size_t>(lanes > 1 ? 8 : 64, limit);
}

size_t launch_work_group(const DeviceInfo& device, size_t work_group, bool chosen, size_t items) {
  if (chosen || !device.is_cpu) return work_group;
  const size_t groups = 8 * std::max<size_t>(device.compute_units, 1);
  while (work_group > 1 && items < groups * work_group) work_group /= 2;
  return work_group;
}

ClEvent::~ClEvent() {
  if (event) clReleaseEvent(event);
}

ClEvent enqueue_kernel(ClContext& cl, cl_kernel kernel, size_t items, size_t work_group, size_t offset) {
  if (work_group == 0 && items > 0)
    for (work_group = 64; items % work_group != 0;) work_group /= 2;
  size_t global = items;
  if (work_group > 0) global = (items + work_group - 1) / work_group * work_group;
  cl_event event = nullptr;
  CL_CHECK(clEnqueueNDRangeKernel(cl.queue, kernel, 1, offset > 0 ? &offset : nullptr, &global,
                                  work_group > 0 ? &work_group : nullptr, 0, nullptr, &event));
  return ClEvent(event);
}

double kernel_event_ms(const ClEvent& event) {
  cl_ulong start = 0, end = 0;
  CL_CHECK(clGetEventProfilingInfo(event.event, CL_PROFILING_COMMAND_START, sizeof(start), &start, nullptr));
  CL_CHECK(clGetEventProfilingInfo(event.event, CL_PROFILING_COMMAND_END, sizeof(end), &end, nullptr));
  return double(end - start) * 1e-6;
}

double run_kernel(ClContext& cl, cl_kernel kernel, size_t items, size_t work_group, size_t offset) {
  ClEvent event = enqueue_kernel(cl, kernel, items, work_group, offset);
  CL_CHECK(clWaitForEvents(1, &event.event));
  return kernel_event_ms(event);
}

bool device_has_extension(const DeviceInfo& d, const char* name) {
  size_t size = 0;
  CL_CHECK(clGetDeviceInfo(d.device, CL_DEVICE_EXTENSIONS, 0, nullptr, &size));
  std::string ext(size, '\0');
  CL_CHECK(clGetDeviceInfo(d.device, CL_DEVICE_EXTENSIONS, size, ext.data(), nullptr));
  return (" " + ext + " ").find(std::string(" ") + name + " ") != std::string::npos;
}
