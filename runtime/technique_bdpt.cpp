// Bidirectional path tracing with MIS over every strategy (kernels/bdpt.cl); its light subpaths are light
// tracing's, its film the same splat film.
#include "runtime/device.h"
#include "runtime/film.h"
#include "runtime/light_transport.h"
#include "runtime/technique.h"

Technique bdpt_technique() {
  Technique t = light_technique();
  t.name = "bdpt";
  t.id = PC_INTEGRATOR_BDPT;
  t.summary = "bidirectional path tracing, every strategy weighted by MIS";
  t.kernel_file = "bdpt.cl";
  t.options = {lanes_option("samples")};  // light tracing's lanes
  t.phases = {{"render", "bdpt_pass", {"lt", "emission_cdf", "film", "stats", "light_vertices", "unit"}, {}}};
  // Each work item keeps its light subpath in device memory (max_depth slots): units as large as it allows.
  t.buffers = {{"light_vertices", light_vertex_bytes}};
  t.max_unit_items = [](const TechniqueSizes& s) { return light_vertex_unit_paths(s, 0); };
  return t;
}
