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
  t.phases = {{"render", "bdpt_pass", {"lt", "emission_cdf", "film", "stats", "unit"}}};
  t.max_depth_limit = kBdptMaxDepth;  // each light subpath is kept in private memory
  t.build_options = [](const TechniqueBuild& b) {
    return splat_build_options(b) + " -DPC_BDPT_MAX_VERTICES=" + std::to_string(std::max<uint32_t>(b.max_depth, 1));
  };
  return t;
}
