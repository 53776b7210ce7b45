// Path tracing with next-event estimation and MIS (kernels/integrator.cl), over 1, 8 or 16 SIMD lanes.
#include "runtime/device.h"
#include "runtime/film.h"
#include "runtime/renderer.h"
#include "runtime/technique.h"

Technique path_technique() {
  Technique t;
  t.name = "path";
  t.id = PC_INTEGRATOR_PATH;
  t.summary = "unidirectional path tracing with next-event estimation and MIS";
  t.kernel_file = "integrator.cl";
  t.phases = {{"render", "render_pass", {"film", "stats", "unit"}, {}}};
  t.layers = {{"radiance", PC_LAYER_ORDERED, PC_RADIANCE_WORDS}};
  t.units = UnitKind::pixels;
  t.lanes = true;
  t.options = {{"lanes", "1, 8 or 16 (paths per work item; the same pixels)", [](double v, RenderOptions& o) {
                  if (v != 1 && v != 8 && v != 16) return false;
                  o.lanes = uint32_t(v);
                  return true;
                }}};
  t.build_options = [](const TechniqueBuild& b) {
    return b.lanes > 1 ? " -DPC_LANES=" + std::to_string(b.lanes) : std::string();  // kernels/lanes.cl
  };
  t.develop = [](Film& film, const LightTransportHeader&, uint64_t*) { develop_radiance(film); };
  return t;
}
