// The OpenCL unit worker (runtime/unit_worker.h): one device of a render, its context, the technique's
// kernel (and the AOV pass's) built for it, the scene uploaded to it and a copy of the film. It runs work
// units one at a time, each as named, timed launches, and knows nothing of the others;
// runtime/renderer.cpp runs one per device, each in a thread of its own.
#pragma once
#include <cstdint>
#include <memory>
#include <deque>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "runtime/device.h"
#include "runtime/kernel_program.h"
#include "runtime/scene_buffers.h"
#include "runtime/unit_worker.h"

class DeviceWorker : public UnitWorker {
 public:
  explicit DeviceWorker(const DeviceInfo& device);  // a context of its own
  explicit DeviceWorker(ClContext& borrowed);       // the caller's context (tests)
  ClContext& cl() { return *cl_; }

  void prepare(const DeviceScene& scene, const SceneHeader& header, const WorkerSettings& settings) override;
  uint64_t probe(uint32_t count, uint32_t spp) override;
  UnitOutput run(const WorkUnit& unit, const std::vector<uint32_t>* input) override;
  WorkerReport report() const override;

 private:
  // One launch of a unit: a kernel, its work-group size and how many of the unit's pixels a work item takes.
  struct Phase {
    std::string name;
    std::unique_ptr<ClKernel> kernel;
    cl_uint first_unit_arg = 0;
    size_t work_group = 0;
    uint32_t item_pixels = 1;
    std::function<size_t(uint32_t count, uint32_t pixels, uint32_t item_pixels)> items;  // TechniquePhase::items
    bool strided = true;  // takes pixel_stride (pixel units and the AOV pass; light paths are not strided)
  };
  // Runs every phase over pixels (or paths) pixel_begin + i * stride, i < count, samples [s0, s0 + sn).
  void set_unit_args(Phase& p, uint32_t pixel_begin, uint32_t pixel_count, uint32_t pixel_stride,
                     uint32_t sample_begin, uint32_t sample_count);
  // Each phase launched once over no pixels (its kernel does nothing for a count of 0): PoCL generates a
  // kernel's code for its work-group size at its first launch (seconds, unless its cache has it), which
  // then counts as the kernel build instead of the first unit's time (and the schedule's first rate).
  void first_launches();
  void launch(uint32_t pixel_begin, uint32_t pixel_count, uint32_t pixel_stride, uint32_t sample_begin,
              uint32_t sample_count, UnitOutput* out);
  void clear_film();
  void clear_commutative_layers();
  void read_commutative_layers(std::vector<uint32_t>& out);

  std::unique_ptr<ClContext> owned_;
  ClContext* cl_;
  const Technique* technique_ = nullptr;
  FilmLayout layout_;
  std::optional<KernelProgram> program_, aov_program_;
  std::unique_ptr<SceneBuffers> scene_;
  std::vector<Phase> phases_;
  ClBuffer film_, stats_, light_header_, emission_cdf_, aov_header_, prim_shapes_, instance_shapes_;
  std::deque<ClBuffer> technique_buffers_;  // Technique::buffers, in order (a deque: bound by address)
  uint32_t lanes_ = 1;
  bool work_group_chosen_ = false;  // --work-group: every launch takes it (else launch_work_group adapts it)
  uint64_t private_bytes_ = 0;
  double first_launch_ms_ = 0;  // first_launches(): PoCL's code generation, part of the kernel build
  uint32_t unit_items_ = 0;  // the largest unit it takes (technique_unit_items)
  std::map<std::string, uint64_t> buffer_bytes_;  // the technique's buffers
  DeviceFault fault_;
  uint64_t units_run_ = 0;
};
