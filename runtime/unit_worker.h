// A unit worker: whatever runs a render's work units (runtime/render_schedule.h) for the render loop
// (runtime/renderer.cpp). Today the OpenCL device worker (runtime/device_worker.h); a worker that stands
// for another process (MPI) is one more implementation. The loop knows a worker only through this: it
// prepares it, probes it, hands it units with their input and gets back outputs that own their payload.
#pragma once
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "kernels/shared/types.h"
#include "runtime/film_layout.h"
#include "runtime/light_transport.h"
#include "runtime/render_schedule.h"
#include "scene/device_scene.h"

struct Technique;

// Test-only misbehaviour of one device (RenderOptions::faults).
struct DeviceFault {
  double delay_seconds = 0;     // added before every unit: a device that lags
  int64_t fail_after_units = -1;  // >= 0: every unit after this many throws, as a lost device would
  bool perturb = false;         // build with PC_DEBUG_PERTURB: a device whose arithmetic differs in one operation
};

struct WorkerSettings {
  const Technique* technique = nullptr;
  FilmLayout layout;          // the film: the technique's layers, then the AOVs
  AovHeader aov{};            // where the AOV pass writes (when the layout has AOVs)
  std::string build_options;  // kernel_options(features) and debug flags
  size_t work_group = 0;      // 0: 64, or the kernel's limit if lower
  DeviceFault fault;
  uint32_t lanes = 0;         // techniques over lanes: 1, 8 or 16 paths per work item; 0: path_lanes(device)
  const LightTransportSetup* light = nullptr;  // techniques with emission: the header and emission distribution
  uint32_t max_depth = 0;
  bool splat_pairs = false;   // splat with 32-bit word pairs even where 64-bit atomics exist (tests)
};

// A named launch of a unit and its device time.
struct PhaseTime {
  std::string name;  // "render" (the technique's kernel), "aov"
  double ms = 0;
};

// What a unit gives back. Its payload is the unit's part of the film (FilmLayout): for each ordered layer
// in layout order the words of the unit's pixels, and for each commutative layer its words over the whole
// image (from cleared sums: the unit's own contribution, added into the film by the loop).
struct UnitOutput {
  UnitStats stats{};
  uint64_t splat_overflows = 0;  // fixed-point splats too large for the scale (a hazard)
  uint64_t light_vertices = 0;   // light vertices kept (bdpt, the merging integrators)
  double seconds = 0;    // the unit's wall time on the worker: upload, launches, read-back
  double kernel_ms = 0;  // the launches alone
  uint64_t transfer_bytes = 0;  // sent to and from another process (runtime/ranks.h), both ways
  std::vector<PhaseTime> phases;
  std::vector<uint32_t> ordered;
  std::vector<uint32_t> commutative;
};

// What the render's statistics say of a worker's set-up.
struct WorkerReport {
  double kernel_build_ms = 0;  // its programs' builds (or cache loads) and the driver's code generation at their first launches, summed
  bool kernel_from_cache = false;
  std::string kernel_options;  // the technique's program's
  uint64_t kernel_private_bytes = 0;  // the most private memory per work item of the technique's kernels
  uint32_t lanes = 1;
  uint32_t unit_items = 0;  // the largest unit (pixels or paths) it takes (Technique::max_unit_items); 0: any
  std::map<std::string, uint64_t> buffers;  // the technique's device buffers and their bytes
};

class UnitWorker {
 public:
  virtual ~UnitWorker() = default;
  // Builds or loads its kernels, uploads the scene with this render's header, clears its film copy.
  // UsageError for settings the worker cannot run (a work-group size beyond its limit).
  virtual void prepare(const DeviceScene& scene, const SceneHeader& header, const WorkerSettings& settings) = 0;
  // Samples [0, spp) of up to `count` pixels (or light paths) spread evenly over the film, from a cleared
  // film: a hash of everything they wrote and of the counters. Clears the film copy again.
  virtual uint64_t probe(uint32_t count, uint32_t spp) = 0;
  // Runs a unit. input: when unit.upload, the film's ordered layers over the unit's pixels (as
  // UnitOutput::ordered), else nullptr.
  virtual UnitOutput run(const WorkUnit& unit, const std::vector<uint32_t>* input) = 0;
  virtual WorkerReport report() const = 0;
};
