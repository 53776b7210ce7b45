// The gathering integrators (kernels/gather.cl): instant radiosity and stochastic radiosity. An iteration is a
// sample: its light paths are traced first (each unit traces all of them: they are few, or a unit is a
// device's share of the image), then every pixel of the unit gathers from them. Pixel units, the path
// integrator's film: each pixel's samples are added in order, so any split gives the same bits.
#include <algorithm>
#include <cmath>
#include <numeric>

#include "runtime/device.h"
#include "runtime/errors.h"
#include "runtime/film.h"
#include "runtime/light_transport.h"
#include "runtime/renderer.h"
#include "runtime/technique.h"
#include "scene/device_scene.h"

namespace {

// kernels/gather.cl's PC_BIN_WORDS: a primitive's three 64-bit power sums.
constexpr size_t kBinBytes = 6 * sizeof(uint32_t);
// kernels/gather.cl's shoot_items: the vertex slots of radiosity's shooting, whatever the unit.
constexpr size_t kShootSlots = size_t(1) << 17;

Technique gather_technique(const char* name, uint32_t id, const char* summary, uint32_t most_light_paths) {
  Technique t;
  t.name = name;
  t.id = id;
  t.summary = summary;
  t.kernel_file = "gather.cl";
  t.layers = {{"radiance", PC_LAYER_ORDERED, PC_RADIANCE_WORDS}};
  t.units = UnitKind::pixels;
  t.per_sample = true;
  t.cpu_unit_seconds = 1.0;
  t.build_options = splat_build_options;
  t.develop = [](Film& film, const LightTransportHeader&, uint64_t*) { develop_radiance(film); };
  t.options = {count_option("light_paths", "light paths per iteration", most_light_paths, &RenderOptions::light_paths)};
  return t;
}

// The light paths of an iteration: the option's, else `fallback` (0: one per pixel).
uint32_t light_paths_of(const DeviceScene& scene, const RenderOptions& o, uint32_t fallback) {
  if (o.light_paths > 0) return o.light_paths;
  return fallback > 0 ? fallback : std::max<uint32_t>(1, scene.header.width * scene.header.height);
}

}  // namespace

Technique instant_radiosity_technique() {
  Technique t = gather_technique("instant_radiosity", PC_INTEGRATOR_INSTANT_RADIOSITY,
                                 "instant radiosity: virtual point lights of a few light paths, gathered with shadow rays",
                                 // every vertex of every light path is kept on the device at once
                                 1u << 16);
  t.phases = {{"light", "ir_light", {"lt", "emission_cdf", "stats", "light_vertices", "vertex_counts", "unit"}, {}},
              {"gather", "ir_gather", {"lt", "film", "stats", "light_vertices", "vertex_counts", "unit"}, {}}};
  t.buffers = {{"light_vertices", [](const TechniqueSizes& s) { return size_t(s.light_paths) * light_vertex_slots(s) * sizeof(LightVertex); }},
               {"vertex_counts", [](const TechniqueSizes& s) { return size_t(s.light_paths) * sizeof(uint32_t); }}};
  t.options.push_back(number_option("clamp", "a number >= 0 (the largest geometry term cos cos / d^2, in 1 / scene units^2; 0: none)",
                                    [](double v) { return v >= 0 && std::isfinite(v); }, &RenderOptions::clamp));
  t.key_settings = [](const RenderOptions& o) { return std::vector<double>{double(o.light_paths), o.clamp}; };
  t.setup_light = [](LightTransportSetup& setup, const DeviceScene& scene, const RenderOptions& o) {
    setup.header.light_paths = light_paths_of(scene, o, 64);
    // The clamp is in scene units; the device's coordinates are the scene's shifted (DeviceOrigin), not scaled.
    setup.header.clamp = float(o.clamp);
  };
  return t;
}

Technique radiosity_technique() {
  Technique t = gather_technique("radiosity", PC_INTEGRATOR_RADIOSITY,
                                 "stochastic radiosity: light paths into per-triangle power sums, shown by a final gather",
                                 1u << 24);
  t.phases = {{"clear", "rad_clear", {"bins", "unit"}, {}},
              {"shoot", "rad_shoot", {"lt", "emission_cdf", "stats", "light_vertices", "bins", "unit"}, {}},
              {"display", "rad_display", {"lt", "film", "stats", "bins", "unit"}, {}}};
  t.buffers = {{"light_vertices", [](const TechniqueSizes& s) {
                  const size_t slots = light_vertex_slots(s);
                  return std::max<size_t>(1, kShootSlots / slots) * slots * sizeof(LightVertex);
                }},
               {"bins", [](const TechniqueSizes& s) { return size_t(s.prims) * kBinBytes; }}};
  t.options.push_back(flag_option("final_gather", &RenderOptions::final_gather));
  t.key_settings = [](const RenderOptions& o) { return std::vector<double>{double(o.light_paths), o.final_gather ? 1.0 : 0.0}; };
  t.setup_light = [](LightTransportSetup& setup, const DeviceScene& scene, const RenderOptions& o) {
    LightTransportHeader& lt = setup.header;
    lt.light_paths = light_paths_of(scene, o, 0);
    lt.final_gather = o.final_gather ? 1 : 0;
    // A light path carries about the scene's power (luminance; a saturated colour's channel up to ~14
    // times it) to each vertex: every path's every vertex in one primitive stays below 2^62.
    const double power = std::accumulate(setup.power.begin(), setup.power.end(), 0.0);
    const double peak = 16 * std::max(power, 1e-30) * double(lt.light_paths) * std::max<uint32_t>(o.max_depth, 1);
    lt.bin_scale = std::ldexp(1.0f, std::clamp(int(std::floor(62 - std::log2(peak))), -100, 100));
  };
  t.check_scene = [](const DeviceScene& scene) {
    if (scene.instance_count > 0)
      throw UsageError("the radiosity integrator keeps one power sum per triangle and takes no instanced meshes (the scene places " +
                       std::to_string(scene.instance_count) + "); flatten them into plain meshes, or choose another integrator");
    // What the display shows as diffuse: the non-delta materials that are not Lambertian.
    static const char* const kNames[] = {"diffuse", "oren_nayar", "phong", "mirror", "dielectric", "rough_conductor", "plastic", "thin_dielectric"};
    std::vector<bool> seen(std::size(kNames), false);
    for (const Material& m : scene.materials)
      if (m.type != PC_MAT_DIFFUSE && m.type != PC_MAT_MIRROR && m.type != PC_MAT_DIELECTRIC &&
          m.type != PC_MAT_THIN_DIELECTRIC && m.type < seen.size())
        seen[m.type] = true;
    std::string list;
    for (size_t i = 0; i < seen.size(); ++i)
      if (seen[i]) list += (list.empty() ? "" : ", ") + std::string(kNames[i]);
    if (list.empty()) return std::vector<std::string>{};
    return std::vector<std::string>{"radiosity: the " + list +
                                    " materials reflect the solution as diffuse surfaces of their colour (where "
                                    "the final gather does not see them directly)"};
  };
  return t;
}
