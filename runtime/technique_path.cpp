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
  t.options = {lanes_option("paths")};
  t.build_options = lanes_build_option;
  t.develop = [](Film& film, const LightTransportHeader&, uint64_t*) { develop_radiance(film); };
  return t;
}
