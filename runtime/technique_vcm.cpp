// Photon merging (kernels/vcm.cl): vertex connection and merging, bidirectional photon mapping and
// stochastic progressive photon mapping. An iteration is a sample: its light paths are stored on the device,
// a hash grid built over their vertices, and the camera paths merge with them (and, for vcm, connect to
// them as bdpt does); a unit is a range of an iteration's light paths, its merges integer sums.
#include <algorithm>
#include <cmath>

#include "runtime/device.h"
#include "runtime/film.h"
#include "runtime/light_transport.h"
#include "runtime/renderer.h"
#include "runtime/technique.h"

namespace {

// A grid entry of kernels/vcm.cl: a float4.
constexpr size_t kGridEntryBytes = 4 * sizeof(float);
// Merging's factor in vcm's MIS weights: the scene's merge_mis, else 0.25 (see setup_light).
double merge_mis(const RenderOptions& o) { return o.merge_mis > 0 ? o.merge_mis : 0.25; }

// kernels/vcm.cl's grid_table: buckets for a unit of `paths` light paths.
size_t grid_table(uint32_t paths) {
  size_t t = 1;
  while (t < size_t(paths) * PC_GRID_BUCKETS_PER_PATH) t <<= 1;
  return t;
}

Technique merging_technique(const char* name, uint32_t id, uint32_t mode, const char* summary) {
  Technique t = bdpt_technique();
  t.name = name;
  t.id = id;
  t.summary = summary;
  t.kernel_file = "vcm.cl";
  t.per_sample = true;
  // Buffers for the largest unit (light paths [b, b + c) of an iteration): max_depth vertex slots per path,
  // its vertex count, the grid's buckets (a power of two >= PC_GRID_BUCKETS_PER_PATH c, one end and the prefix
  // sum's block offsets)
  // and entries (a vertex's position and slot: 4 words).
  t.buffers = {{"light_vertices", light_vertex_bytes},
               {"vertex_counts", [](const TechniqueSizes& s) { return s.unit_items * sizeof(uint32_t); }},
               {"cells", [](const TechniqueSizes& s) { return (grid_table(s.unit_items) + 1 + PC_SCAN_BLOCKS) * sizeof(uint32_t); }},
               {"entries", [](const TechniqueSizes& s) { return s.unit_items * light_vertex_slots(s) * kGridEntryBytes; }}};
  t.max_unit_items = [](const TechniqueSizes& s) {
    // a path's entries, its vertex count and its buckets (twice PC_GRID_BUCKETS_PER_PATH: the power of two)
    return light_vertex_unit_paths(s, light_vertex_slots(s) * kGridEntryBytes + (1 + 2 * PC_GRID_BUCKETS_PER_PATH) * sizeof(uint32_t));
  };
  // The grid's scatter takes a light path a work item, whatever the lanes.
  const auto one_per_path = [](uint32_t count, uint32_t, uint32_t) { return size_t(count); };
  const std::vector<std::string> light = {"lt", "emission_cdf", "film", "stats", "light_vertices", "vertex_counts", "cells", "unit"};
  t.phases = {
      {"clear", "vcm_clear", {"cells", "unit"}, [](uint32_t count, uint32_t, uint32_t) { return grid_table(count) + 1; }},
      {"light", "vcm_light", light, {}},
      {"scan", "vcm_scan_blocks", {"cells", "unit"}, [](uint32_t, uint32_t, uint32_t) { return size_t(PC_SCAN_BLOCKS); }},
      {"scan_offsets", "vcm_scan_offsets", {"cells", "unit"}, [](uint32_t, uint32_t, uint32_t) { return size_t(1); }},
      {"scan_add", "vcm_scan_add", {"cells", "unit"}, [](uint32_t, uint32_t, uint32_t) { return size_t(PC_SCAN_BLOCKS); }},
      {"scatter", "vcm_scatter", {"lt", "light_vertices", "vertex_counts", "cells", "entries", "unit"}, one_per_path},
      {"camera", "vcm_camera",
       {"lt", "emission_cdf", "film", "stats", "light_vertices", "vertex_counts", "cells", "entries", "unit"},
       [](uint32_t, uint32_t pixels, uint32_t item_pixels) { return size_t((pixels + item_pixels - 1) / item_pixels); }},
  };
  // A unit traces every camera path of its iteration: whole iterations where the time allows.
  t.cpu_unit_seconds = 2.0;
  t.key_settings = [](const RenderOptions& o) {
    return std::vector<double>{o.radius, o.alpha, o.merge ? 1.0 : 0.0, merge_mis(o)};
  };
  t.setup_light = [mode](LightTransportSetup& setup, const DeviceScene& scene, const RenderOptions& o) {
    LightTransportHeader& lt = setup.header;
    lt.vcm_mode = o.merge ? mode : mode & ~PC_VCM_MERGE;
    // vcm's merges compete with its connections, which sample light between diffuse surfaces with no bias:
    // half a pixel's footprint there (its bias on the Cornell box at 1024 spp a quarter of the whole
    // footprint's, glass-metal's caustics under a spot light as noisy; docs/light-transport.md). bpm and
    // sppm have nothing but merging: the whole footprint, for the photons a pixel gathers.
    const double footprints = mode & PC_VCM_CONNECT ? 0.5 : 1.0;
    lt.radius = float(o.radius > 0 ? o.radius : footprints * default_merging_radius(scene, lt));
    lt.alpha = float(o.alpha);
    // Merging's factor in the MIS weights: SmallVCM's balance heuristic (1) counts a merge as a sample of
    // density pi r^2 N p and misses the noise of how many light vertices fall within r; a quarter leaves the
    // paths connections sample mostly to them (vcm's relMSE on the Cornell box and on glass-metal under a
    // spot light 1.3 to 1.4 times lower at 4 to 256 spp; docs/light-transport.md).
    // bpm and sppm weigh nothing against their merges: 1, which changes nothing.
    lt.merge_mis = mode & PC_VCM_CONNECT ? float(merge_mis(o)) : 1.0f;
  };
  t.options = {lanes_option("light and camera paths"),
               number_option("radius", "a radius > 0 (scene units)", [](double v) { return v > 0 && std::isfinite(v); },
                             &RenderOptions::radius),
               number_option("alpha", "a number in (0, 1]", [](double v) { return v > 0 && v <= 1; }, &RenderOptions::alpha)};
  return t;
}

}  // namespace

Technique vcm_technique() {
  Technique t = merging_technique("vcm", PC_INTEGRATOR_VCM, PC_VCM_CONNECT | PC_VCM_MERGE,
                                  "vertex connection and merging: bdpt's strategies and photon merging, weighted by MIS");
  t.options.push_back(flag_option("merge", &RenderOptions::merge));
  t.options.push_back(number_option("merge_mis", "a number in (0, 1] (merging's factor in the MIS weights)",
                                    [](double v) { return v > 0 && v <= 1; }, &RenderOptions::merge_mis));
  return t;
}

Technique bpm_technique() {
  return merging_technique("bpm", PC_INTEGRATOR_BPM, PC_VCM_MERGE,
                           "bidirectional photon mapping: merging at every camera vertex, weighted by MIS");
}

Technique sppm_technique() {
  return merging_technique("sppm", PC_INTEGRATOR_SPPM, PC_VCM_MERGE | PC_VCM_SPPM,
                           "stochastic progressive photon mapping with a global radius schedule");
}
