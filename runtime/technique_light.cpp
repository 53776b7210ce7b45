// Light tracing (kernels/light_integrator.cl): light paths connected to the camera, splatted in fixed point,
// over 1, 8 or 16 SIMD lanes.
#include "runtime/device.h"
#include "runtime/film.h"
#include "runtime/light_transport.h"
#include "runtime/technique.h"

Technique light_technique() {
  Technique t;
  t.name = "light";
  t.id = PC_INTEGRATOR_LIGHT;
  t.summary = "light tracing: light paths connected to the camera";
  t.kernel_file = "light_integrator.cl";
  t.phases = {{"render", "light_pass", {"lt", "emission_cdf", "film", "stats", "unit"}, {}}};
  t.layers = {{"splats", PC_LAYER_COMMUTATIVE, 2 * PC_SPLAT_WORDS}};
  t.units = UnitKind::paths;
  // A unit also clears, reads back and adds the whole splat film (96 bytes a pixel, ~20 ms at 512 x 512 on
  // a CPU device): longer units keep that under 2 % (bdpt 7.2 s -> 6.8 s on the Cornell box).
  t.cpu_unit_seconds = 1.0;
  t.lanes = true;
  t.options = {lanes_option("light paths")};
  t.build_options = [](const TechniqueBuild& b) { return splat_build_options(b) + lanes_build_option(b); };
  t.develop = develop_splats;
  return t;
}
