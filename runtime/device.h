// OpenCL platforms and devices: listing, choosing one by index or name, and the context and queue.
#pragma once
#include <cstdint>
#include <mutex>
#include <string>
#include <utility>
#include <vector>

#include "runtime/cl_check.h"

struct DeviceInfo {
  cl_platform_id platform = nullptr;
  cl_device_id device = nullptr;
  std::string platform_name, platform_version, name, version, driver_version, opencl_c_version;
  bool is_gpu = false, is_cpu = false;
  cl_uint compute_units = 0;
  cl_ulong global_memory = 0, max_alloc = 0;
  size_t max_work_group = 0;
  // CL_DEVICE_SINGLE_FP_CONFIG: correctly rounded float divide and sqrt (then every kernel is built with
  // -cl-fp32-correctly-rounded-divide-sqrt), and denormals (else they may be flushed to zero).
  bool correctly_rounded_divide_sqrt = false, denormals = false;
  cl_uint preferred_float_width = 1;  // CL_DEVICE_PREFERRED_VECTOR_WIDTH_FLOAT
  bool sub_device = false;  // a partition of `device` made by partition_device (released with its context)
  size_t index = 0;         // in list_devices()
};

// Every device of every platform, in platform order; the index is what `--device N` takes.
std::vector<DeviceInfo> list_devices();

// "" picks the first GPU, else the first CPU device; a number picks by index; anything else is a
// case-insensitive substring of the device or platform name. No match is a UsageError. The default
// never picks Oclgrind (an interpreter for debugging that calls itself a GPU): it must be named.
DeviceInfo select_device(const std::string& selector);

// Whether the device lists the OpenCL extension `name` (CL_DEVICE_EXTENSIONS).
bool device_has_extension(const DeviceInfo& device, const char* name);

// Oclgrind: an interpreter for debugging that calls itself a GPU. Never a default device, and its 21.10
// cannot run optimised kernels (runtime/kernel_program.cpp).
bool is_oclgrind(const DeviceInfo& device);
// PoCL (Portable Computing Language), which keeps its compiled programs in a cache of its own.
bool is_pocl(const DeviceInfo& device);

// The BVH layout for the device, 4, 8 or 16 children a node (kernels/shared/types.h): on CPU devices 16
// where the preferred float vector is 16 wide (AVX-512: the float16 slab test is one instruction, and the
// tree half as deep), else 8 (a float8 test is one AVX instruction, or two SSE ones); 4 on the others.
// PATHCL_BVH_WIDTH=4, 8 or 16 chooses for every device (tests and benchmarks of the layouts); any other
// value is a UsageError. The hits, and so the images, are the same in all.
uint32_t bvh_width(const DeviceInfo& device);
// The device scene's layout bit of a BVH width (scene/device_scene.h: kBvhLayout4, 8, 16), and the layouts
// that the devices read together.
uint32_t bvh_layout(uint32_t width);
uint32_t bvh_layouts(const std::vector<DeviceInfo>& devices);

// Paths per work item of the path integrator on the device (kernels/lanes.cl): 1 on GPUs and Oclgrind,
// whose work items are the SIMD lanes already; on CPU devices 16 where the preferred float vector is 16
// wide (AVX-512: the fastest there, 16 > 8 > 1 on the Cornell box, docs/heterogeneous.md), else 8.
// PATHCL_LANES=1, 8 or 16 chooses for every device (tests, benchmarks); any other value is a UsageError.
uint32_t path_lanes(const DeviceInfo& device);

// A comma-separated list of selectors as select_device takes them, "gpu" (every GPU), "cpu" (the first CPU
// device: the CPU devices of several platforms are the same cores, which would only compete), or "all"
// for every device; each device at most once, in the order given. "" is the default device alone. The
// types never pick Oclgrind.
std::vector<DeviceInfo> select_devices(const std::string& selectors);

// A sub-device of a CPU device with `units` of its compute units (clCreateSubDevices by counts), so that
// the rest stay free for the host, or the device itself when it cannot be partitioned.
DeviceInfo partition_device(const DeviceInfo& device, cl_uint units);

// A context and an in-order profiling queue on one device.
struct ClContext {
  DeviceInfo info;
  cl_context context = nullptr;
  cl_command_queue queue = nullptr;
  // For a caller that builds the same programs again and again on this context (fuzz/fuzz_render.cpp
  // renders thousands of scenes): build_kernel_program then keeps the last kKeptPrograms programs it made
  // here and hands the same one out again for the same source and options, instead of loading the cached
  // binary each time (tens of milliseconds on PoCL). Off by default: a render reports its real build.
  bool keep_programs = false;
  static constexpr size_t kKeptPrograms = 64;
  std::vector<std::pair<uint64_t, cl_program>> kept_programs;  // key, retained; oldest first
  std::mutex kept_programs_mutex;
  explicit ClContext(const DeviceInfo& device);
  ~ClContext();
  ClContext(const ClContext&) = delete;
  ClContext& operator=(const ClContext&) = delete;
};

// A device buffer that is released with its owner.
struct ClBuffer {
  cl_mem mem = nullptr;
  ClBuffer() = default;
  ClBuffer(ClContext& cl, cl_mem_flags flags, size_t bytes, const void* host = nullptr);
  ~ClBuffer();
  ClBuffer(ClBuffer&& o) noexcept : mem(o.mem) { o.mem = nullptr; }
  ClBuffer& operator=(ClBuffer&& o) noexcept;
  ClBuffer(const ClBuffer&) = delete;
};

// Uploads a vector; an empty one gets a buffer of one zeroed element, since OpenCL has no empty buffers.
template <class T>
ClBuffer upload(ClContext& cl, const std::vector<T>& data) {
  static const T zero{};
  return data.empty() ? ClBuffer(cl, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, sizeof(T), &zero)
                      : ClBuffer(cl, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, sizeof(T) * data.size(), data.data());
}

// The work-group size a kernel runs in: `requested` (a --work-group option) if the device allows it, else
// UsageError naming `what`; 0 chooses 64 work items, or 8 where each holds the rays or paths of lanes > 1
// (PoCL keeps a group's private memory on its stack), or the kernel's limit if lower. One size for every
// launch: PoCL compiles a work-group function per local size, and left to itself it chooses the local size
// from the global size's factors (4094 of 53,222 packets of 16 rays: 13 groups for 2 threads).
size_t kernel_work_group(const ClContext& cl, cl_kernel kernel, size_t requested, uint32_t lanes, const std::string& what);

// The work group of one launch of `items` work items of a kernel whose work group is `work_group`
// (kernel_work_group's): itself where the user chose it (`chosen`, a --work-group option) or the device is no
// CPU; on a CPU device, whose work groups each run whole on one of its threads, halved (down to 1) while the
// launch would give its compute units fewer than 8 groups each. A small image's launch is few items of W x 16
// pixels (the Cornell box at 96 x 72 with 16 lanes: 27), and in groups of 8 its 2 threads took the time of
// 16 items where 14 would do (one thread idle for most of the second round). Any size gives the same bits;
// PoCL compiles one work-group function for every size (list_devices' POCL_WORK_GROUP_SPECIALIZATION=0).
size_t launch_work_group(const DeviceInfo& device, size_t work_group, bool chosen, size_t items);

// Runs a 1-D kernel over work items [offset, offset + items) (rounded up to the work-group size) and returns
// the kernel's time on the device in milliseconds, from profiling events. work_group 0: the largest power of
// two up to 64 that divides items (the tests' kernels, which have no bound on their index), not the driver's
// choice: a driver that specializes work-group functions (PoCL unless POCL_WORK_GROUP_SPECIALIZATION=0, which
// list_devices sets) compiles one per local size and chooses it from the global size's factors, so a kernel
// launched over many sizes was compiled many times (light_pdf_bins 23 times in a suite run).
double run_kernel(ClContext& cl, cl_kernel kernel, size_t items, size_t work_group = 0, size_t offset = 0);
// A launch's profiling event, released with its owner (also when a later launch or the wait throws).
struct ClEvent {
  cl_event event = nullptr;
  ClEvent() = default;
  explicit ClEvent(cl_event e) : event(e) {}
  ~ClEvent();
  ClEvent(ClEvent&& o) noexcept : event(o.event) { o.event = nullptr; }
  ClEvent& operator=(ClEvent&&) = delete;
  ClEvent(const ClEvent&) = delete;
};
// The launch of run_kernel without the wait: its event, for kernel_event_ms once it has completed. Launches
// one after another on the in-order queue run in order; waiting only for the last spares the device's threads
// an idle round trip to the host between them.
ClEvent enqueue_kernel(ClContext& cl, cl_kernel kernel, size_t items, size_t work_group = 0, size_t offset = 0);
// A completed launch's time on the device in milliseconds, from its profiling event.
double kernel_event_ms(const ClEvent& event);
