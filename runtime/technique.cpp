#include "runtime/technique.h"

#include <algorithm>
#include <cmath>
#include <mutex>

#include <nlohmann/json.hpp>

#include "runtime/errors.h"
#include "runtime/renderer.h"

namespace {
std::mutex registry_mutex;

std::vector<Technique>& registry() {
  // The registry: one line per technique.
  static std::vector<Technique> list = {path_technique(), light_technique(), bdpt_technique(),
                                         vcm_technique(),  bpm_technique(),   sppm_technique(),
                                         instant_radiosity_technique(), radiosity_technique(), mlt_technique()};
  return list;
}
}  // namespace

const std::vector<Technique>& techniques() { return registry(); }

void register_technique(Technique technique) {
  std::lock_guard<std::mutex> lock(registry_mutex);
  for (const Technique& t : registry())
    if (t.name == technique.name || t.id == technique.id)
      throw std::logic_error("technique " + technique.name + ": its name or id is taken by " + t.name);
  // Registration happens before renders start (a test's set-up): the vector is not read meanwhile.
  registry().push_back(std::move(technique));
}

TechniqueOption lanes_option(const std::string& what) {
  return {"lanes", "1, 8 or 16 (" + what + " per work item; the same pixels)", [](double v, RenderOptions& o) {
            if (v != 1 && v != 8 && v != 16) return false;
            o.lanes = uint32_t(v);
            return true;
          }};
}

std::string lanes_build_option(const TechniqueBuild& b) {
  return b.lanes > 1 ? " -DPC_LANES=" + std::to_string(b.lanes) : std::string();  // kernels/lanes.cl
}

TechniqueOption flag_option(const std::string& name, bool RenderOptions::*field) {
  return {name, "true or false", [field](double v, RenderOptions& o) {
            if (v != 0 && v != 1) return false;
            o.*field = v != 0;
            return true;
          }};
}

TechniqueOption count_option(const std::string& name, const std::string& what, uint32_t most, uint32_t RenderOptions::*field) {
  return {name, "a whole number of " + what + ", 1 to " + std::to_string(most), [most, field](double v, RenderOptions& o) {
            if (!(v >= 1 && v <= most && v == std::floor(v))) return false;
            o.*field = uint32_t(v);
            return true;
          }};
}

TechniqueOption number_option(const std::string& name, const std::string& expected, std::function<bool(double)> fits,
                              double RenderOptions::*field) {
  return {name, expected, [fits, field](double v, RenderOptions& o) {
            if (!fits(v)) return false;
            o.*field = v;
            return true;
          }};
}

std::string technique_list() {
  std::string s;
  const std::vector<Technique>& list = techniques();
  for (size_t i = 0; i < list.size(); ++i)
    s += (i == 0 ? "" : i + 1 == list.size() ? " or " : ", ") + list[i].name;
  return s;
}

const Technique& technique_named(const std::string& name, const std::string& where) {
  for (const Technique& t : techniques())
    if (t.name == name) return t;
  throw UsageError(where + ": unknown integrator \"" + name + "\" (expected " + technique_list() + ")");
}

bool uses_emission(const Technique& t) {
  for (const TechniquePhase& p : t.phases)
    for (const std::string& arg : p.args)
      if (arg == "lt" || arg == "emission_cdf") return true;
  return false;
}

uint32_t technique_unit_items(const Technique& t, TechniqueSizes sizes) {
  sizes.unit_items = 0;
  const uint32_t n = t.max_unit_items ? t.max_unit_items(sizes) : sizes.pixels;
  return std::max(1u, std::min(n, sizes.pixels));
}

std::vector<FilmLayer> technique_layers(const Technique& t, uint32_t max_depth) {
  return t.layers_at_depth ? t.layers_at_depth(max_depth) : t.layers;
}

const Technique* technique_with_id(uint32_t id) {
  for (const Technique& t : techniques())
    if (t.id == id) return &t;
  return nullptr;
}

void check_technique_options(const Technique& t, const RenderOptions& options) {
  if (options.lanes != 0 && options.lanes != 1 && options.lanes != 8 && options.lanes != 16)
    throw UsageError("--lanes " + std::to_string(options.lanes) + ": one path per work item (1) or 8 or 16");
  if (options.lanes > 1 && !t.lanes)
    throw UsageError("--lanes " + std::to_string(options.lanes) + ": the " + t.name + " integrator does not run over lanes");
  if (options.max_depth > t.max_depth_limit)
    throw UsageError("max_depth " + std::to_string(options.max_depth) + ": the " + t.name +
                     " integrator takes max_depth up to " + std::to_string(t.max_depth_limit));
  if ((options.debug_bdpt_strategy_s >= 0 || options.debug_bdpt_strategy_t >= 0) && t.name != "bdpt")
    throw UsageError("a single BDPT strategy needs the bdpt integrator, not " + t.name);
}

void apply_technique_options(const Technique& t, const std::string& json_object, const std::string& place,
                             RenderOptions& options) {
  const nlohmann::json j = nlohmann::json::parse(json_object);
  for (const auto& [key, value] : j.items()) {
    const TechniqueOption* option = nullptr;
    for (const TechniqueOption& o : t.options)
      if (o.name == key) option = &o;
    if (!option) {
      std::string known;
      for (const TechniqueOption& o : t.options) known += (known.empty() ? "" : ", ") + o.name;
      throw UsageError(place + "." + key + ": the " + t.name + " integrator has no option \"" + key + "\" (" +
                       (known.empty() ? "it has none" : "it has " + known) + ")");
    }
    // A boolean option takes true or false (as 1 and 0).
    const bool number = value.is_number() || value.is_boolean();
    if (!number || !option->set(value.is_boolean() ? double(value.get<bool>()) : value.get<double>(), options))
      throw UsageError(place + "." + key + ": expected " + option->expected + ", got " + value.dump());
  }
}
