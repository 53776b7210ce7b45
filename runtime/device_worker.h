// One device of a render: its context, the render kernel built for it, the scene uploaded to it and a copy
// of the film's accumulators. It runs work units (runtime/render_schedule.h) one at a time and knows
// nothing of the others; runtime/renderer.cpp runs one per device, each in a thread of its own.
#pragma once
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "runtime/device.h"
#include "runtime/kernel_program.h"
#include "runtime/light_transport.h"
#include "runtime/render_schedule.h"
#include "runtime/scene_buffers.h"

// Test-only misbehaviour of one device (RenderOptions::faults).
struct DeviceFault {
  double delay_seconds = 0;     // added before every unit: a device that lags
  int64_t fail_after_units = -1;  // >= 0: every unit after this many throws, as a lost device would
  bool perturb = false;         // build with PC_DEBUG_PERTURB: a device whose arithmetic differs in one operation
};

// What a unit gives back: its statistics and timings; the accumulators of its pixels (3 per pixel) are in
// the worker's read-back buffer (DeviceWorker::result), valid until its next unit. With the light
// integrator a unit's tiles are light path indices, not pixels: its splats land anywhere, so it gives back
// the whole splat film of the unit (DeviceWorker::splats), cleared before each unit.
struct UnitOutput {
  UnitStats stats{};
  uint64_t splat_overflows = 0;  // light integrator: splats too large for the fixed-point scale (a hazard)
  double seconds = 0;    // the unit's wall time on this device: upload, launch, read-back
  double kernel_ms = 0;  // the launch alone, from profiling events
};

struct WorkerSettings {
  std::string build_options;  // kernel_options(features) and debug flags
  size_t work_group = 0;      // 0: 64, or the kernel's limit if lower
  DeviceFault fault;
  uint32_t integrator = PC_INTEGRATOR_PATH;
  uint32_t lanes = 0;         // path: paths per work item, 1, 8 or 16 (kernels/lanes.cl); 0: path_lanes(device)
  const LightTransportSetup* light = nullptr;  // light, bdpt: the header and emission distribution
  uint32_t max_depth = 0;     // bdpt: the light subpath's vertex array has this many (at least 1)
  bool splat_pairs = false;   // splat with 32-bit word pairs even where 64-bit atomics exist (tests)
};

class DeviceWorker {
 public:
  explicit DeviceWorker(const DeviceInfo& device);  // a context of its own
  explicit DeviceWorker(ClContext& borrowed);       // the caller's context (tests)
  ClContext& cl() { return *cl_; }

  // Builds the render kernel (or loads it from the cache), uploads the scene with this render's header,
  // and clears the film copy. UsageError for a work-group size the device cannot run.
  void prepare(const DeviceScene& scene, const SceneHeader& header, const WorkerSettings& settings);
  // Samples [0, spp) of up to `count` pixels spread evenly over the film, from cleared accumulators; a hash
  // of the accumulators and ray count. Clears the film copy again.
  uint64_t probe(uint32_t count, uint32_t spp);
  // Runs a unit. input: the film's accumulators of the unit's pixels when unit.upload, else nullptr.
  UnitOutput run(const WorkUnit& unit, const std::vector<pc_float4>* input);
  // The accumulators of the last unit's pixels. One buffer reused by every unit: no allocation, and no
  // page faults, per unit.
  const std::vector<pc_float4>& result() const { return result_; }
  // Light integrator: the last unit's splat film, PC_SPLAT_WORDS sums per pixel of the whole image.
  const std::vector<uint64_t>& splats() const { return splats_; }
  bool light() const { return uses_splat_film(integrator_); }  // light tracing or BDPT: the splat film

  const KernelProgram& program() const { return *program_; }
  size_t work_group() const { return work_group_; }
  uint32_t lanes() const { return lanes_; }
  uint64_t private_bytes() const { return private_bytes_; }  // CL_KERNEL_PRIVATE_MEM_SIZE of the render kernel

 private:
  double launch(uint32_t pixel_begin, uint32_t pixel_count, uint32_t pixel_stride, uint32_t sample_begin,
                uint32_t sample_count);
  void clear_film();
  void read_splats();

  std::unique_ptr<ClContext> owned_;
  ClContext* cl_;
  std::optional<KernelProgram> program_;
  std::unique_ptr<SceneBuffers> scene_;
  std::unique_ptr<ClKernel> kernel_;
  ClBuffer film_, stats_, light_header_, emission_cdf_;
  std::vector<pc_float4> result_;
  std::vector<uint64_t> splats_;
  uint32_t integrator_ = PC_INTEGRATOR_PATH;
  uint32_t pixels_ = 0;
  size_t work_group_ = 0;
  uint32_t lanes_ = 1;
  uint64_t private_bytes_ = 0;
  cl_uint first_unit_arg_ = 0;
  DeviceFault fault_;
  uint64_t units_run_ = 0;
};
