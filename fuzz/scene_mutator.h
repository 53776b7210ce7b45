// A structure-aware mutation of fuzz_render's input (fuzz/render_input.h): the scene is parsed as JSON,
// one of its values is changed as a scene file's author (or a bad exporter) might change it, and it is
// written out again, the files after it untouched. Byte-level mutations of the text almost always make
// JSON that the loader refuses (3 inputs in 1000 rendered with them alone); these keep it well formed and
// near the format, with values at the edges of what the loader accepts: about two in three still load.
// fuzz/fuzz_render.cpp uses it for most mutations and to cross two inputs over.
#pragma once
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <iterator>
#include <random>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "fuzz/render_input.h"

namespace fuzz {

namespace scene_mutator_detail {

using Json = nlohmann::ordered_json;  // keeps the keys in the file's order
using Rng = std::minstd_rand;

inline size_t pick(Rng& rng, size_t n) { return n ? std::uniform_int_distribution<size_t>(0, n - 1)(rng) : 0; }

// Names the format uses (docs/scene-format.md), by kind: a name is mostly replaced by one of its kind.
inline const std::vector<std::vector<std::string>>& word_kinds() {
  static const std::vector<std::vector<std::string>> w = {
      {"diffuse", "oren_nayar", "phong", "mirror", "dielectric", "rough_conductor", "plastic"},
      {"mesh", "triangles", "sphere"},
      {"point", "spot", "directional", "environment"},
      {"perspective", "thin_lens"},
      {"box", "tent", "gaussian"},
      {"independent", "stratified", "sobol", "halton"},
      {"repeat", "clamp", "mirror"},
      {"m.obj", "mesh.obj", "tex.png", "env.exr", "mesh.mtl", "missing.obj", "", ".", "./m.obj"}};
  return w;
}

inline std::string random_word(Rng& rng) {
  const auto& kind = word_kinds()[pick(rng, word_kinds().size())];
  return kind[pick(rng, kind.size())];
}

inline const std::vector<std::string>& keys() {
  static const std::vector<std::string> k = {
      "type", "position", "look_at", "up", "fov_y_degrees", "width", "height", "aperture_radius", "focus_distance",
      "filter", "radius", "sigma", "reflectance", "sigma_degrees", "diffuse", "specular", "exponent", "ior",
      "transmittance", "roughness", "eta", "k", "texture", "wrap", "file", "material", "emission", "two_sided",
      "transform", "orient", "smooth", "positions", "indices", "uvs", "center", "flip_normals", "translate", "rotate",
      "scale", "matrix", "axis", "degrees", "intensity", "direction", "outer_angle_degrees", "inner_angle_degrees",
      "irradiance", "radiance", "spp", "max_depth", "seed", "sampler", "lights", "render"};
  return k;
}

// Pieces to add to the scene's materials, shapes and lights.
inline const Json& snippets() {
  static const Json s = Json::parse(R"({
    "materials": [
      {"type": "diffuse", "reflectance": [0.5, 0.5, 0.5]},
      {"type": "diffuse", "reflectance": {"texture": "tex.png", "wrap": "mirror"}},
      {"type": "oren_nayar", "reflectance": [0.8, 0.2, 0.2], "sigma_degrees": 90},
      {"type": "phong", "diffuse": [0.2, 0.2, 0.2], "specular": [0.8, 0.8, 0.8], "exponent": 100000},
      {"type": "mirror"},
      {"type": "dielectric", "ior": 10, "transmittance": [1, 1, 1]},
      {"type": "dielectric", "ior": 0.5},
      {"type": "rough_conductor", "roughness": 0.01, "specular": [0.99, 0.5, 0]},
      {"type": "rough_conductor", "roughness": 1, "eta": [0.2, 0.9, 1.1], "k": [3.9, 2.4, 2.2]},
      {"type": "plastic", "diffuse": [0.5, 0.5, 0.5], "ior": 1.5, "roughness": 0.01},
      {"type": "plastic", "diffuse": [1, 1, 1], "ior": 1.0001}
    ],
    "shapes": [
      {"type": "sphere", "center": [0, 0, 0], "radius": 1, "material": "", "emission": [1, 1, 1]},
      {"type": "sphere", "radius": 1e-20, "flip_normals": true, "material": ""},
      {"type": "mesh", "file": "m.obj", "material": "", "orient": true, "smooth": true},
      {"type": "mesh", "file": "mesh.obj", "material": "", "emission": [2, 2, 2], "two_sided": true},
      {"type": "triangles", "positions": [[0, 0, 0], [1, 0, 0], [0, 1, 0]], "indices": [[0, 1, 2]],
       "uvs": [[0, 0], [1, 0], [0, 1]], "material": ""}
    ],
    "lights": [
      {"type": "point", "position": [0, 1, 0], "intensity": [1, 1, 1]},
      {"type": "spot", "position": [0, 2, 0], "direction": [0, -1, 0], "intensity": [4, 4, 4],
       "outer_angle_degrees": 30, "inner_angle_degrees": 30},
      {"type": "directional", "direction": [0, -1, 0], "irradiance": [1, 1, 1]},
      {"type": "environment", "radiance": [0.5, 0.5, 0.5]},
      {"type": "environment", "file": "env.exr", "scale": 1e-3}
    ],
    "transform": [
      {"scale": [1, 1, -1]},
      {"scale": 1e-6, "rotate": {"axis": [1, 1, 1], "degrees": 90}},
      {"matrix": [[0, 1, 0, 0], [1, 0, 0, 0], [0, 0, 1, 1e6], [0, 0, 0, 1]]}
    ],
    "filter": [{"type": "box"}, {"type": "tent", "radius": 0.01}, {"type": "gaussian", "sigma": 4, "radius": 0.5}]
  })");
  return s;
}

// Mostly a nearby value, else one at an edge of what the loader accepts or of float.
inline double interesting_float(Rng& rng, double x) {
  static const double values[] = {0, -0.0, 1, -1, 0.5, 2, 1e-45, 1e-38, 1e-23, 1e-8, 1e-4, 0.01, 0.0099, 0.999999,
                                  1.000001, 89.9999, 90, 179.999, 180, 10, 10.0001, 1e5, 1e18, 1.5e18, 1e30, 3.4e38};
  std::uniform_real_distribution<double> u(0, 1);
  switch (pick(rng, 8)) {
    case 0: return x * (0.5 + u(rng));
    case 1: return x + (u(rng) - 0.5) * (x == 0 ? 1 : std::abs(x));
    case 2: return u(rng);
    case 3: return x * (1 + (u(rng) - 0.5) * 1e-6);
    case 4: return -x;
    default: return values[pick(rng, std::size(values))];
  }
}

inline int64_t interesting_integer(Rng& rng, int64_t x) {
  static const int64_t values[] = {0, 1, 2, 3, 4, 7, 8, 9, -1, 1023, 1024, 1025, 16384, 16385, 16777216, 16777217,
                                   2147483647, 4294967295, 4294967296};
  switch (pick(rng, 4)) {
    case 0: return int64_t(uint64_t(x) + 1);  // wraps instead of overflowing
    case 1: return int64_t(uint64_t(x) - 1);
    case 2: return int64_t(pick(rng, 10));
    default: return values[pick(rng, std::size(values))];
  }
}

// A value of any kind, for a new key or a replaced value.
inline Json random_value(Rng& rng, const std::vector<Json*>& nodes) {
  switch (pick(rng, 7)) {
    case 0: return interesting_float(rng, 1);
    case 1: return interesting_integer(rng, 1);
    case 2: return random_word(rng);
    case 3: return bool(pick(rng, 2));
    case 4: return Json::array({interesting_float(rng, 1), interesting_float(rng, 1), interesting_float(rng, 1)});
    default: return *nodes[pick(rng, nodes.size())];  // a copy of another part of the scene
  }
}

inline void collect(Json& j, std::vector<Json*>& nodes) {
  nodes.push_back(&j);
  if (j.is_object())
    for (auto& [key, value] : j.items()) collect(value, nodes);
  else if (j.is_array())
    for (Json& value : j) collect(value, nodes);
}

// One change somewhere in the scene.
inline void mutate_once(Json& scene, Rng& rng) {
  std::vector<Json*> nodes;
  collect(scene, nodes);
  // Now and then add a material, shape, light, transform or filter from the snippets: new feature sets.
  if (scene.is_object() && pick(rng, 5) == 0) {
    const Json& s = snippets();
    auto it = s.begin();
    std::advance(it, pick(rng, s.size()));
    Json piece = (*it)[pick(rng, it->size())];
    std::vector<std::string> materials;
    if (scene.contains("materials") && scene["materials"].is_object())
      for (auto& [name, value] : scene["materials"].items()) materials.push_back(name);
    if (piece.contains("material") && !materials.empty()) piece["material"] = materials[pick(rng, materials.size())];
    if (it.key() == "materials") {
      if (!scene["materials"].is_object()) scene["materials"] = Json::object();
      std::string name = materials.empty() || pick(rng, 2) ? "n" + std::to_string(pick(rng, 4)) : materials[pick(rng, materials.size())];
      scene["materials"][name] = piece;
    } else if (it.key() == "shapes" || it.key() == "lights") {
      if (!scene[it.key()].is_array()) scene[it.key()] = Json::array();
      scene[it.key()].push_back(piece);
    } else if (it.key() == "transform") {
      if (scene.contains("shapes") && scene["shapes"].is_array() && !scene["shapes"].empty()) {
        Json& shape = scene["shapes"][pick(rng, scene["shapes"].size())];
        if (shape.is_object()) shape["transform"] = piece;
      }
    } else if (scene.contains("camera") && scene["camera"].is_object()) {
      scene["camera"]["filter"] = piece;
    }
    return;
  }
  Json& node = *nodes[pick(rng, nodes.size())];
  if (pick(rng, 16) == 0) {  // anything may become anything
    node = random_value(rng, nodes);
    return;
  }
  switch (node.type()) {
    case Json::value_t::number_float:
      if (pick(rng, 16) || !(std::abs(node.get<double>()) < 1e18))
        node = interesting_float(rng, node.get<double>());
      else
        node = int64_t(node.get<double>());  // 8.0 -> 8, 0.5 -> 0
      break;
    case Json::value_t::number_integer:
    case Json::value_t::number_unsigned:
      node = pick(rng, 16) ? Json(interesting_integer(rng, node.get<int64_t>())) : Json(node.get<double>() + 0.5);
      break;
    case Json::value_t::string: {
      // Mostly a name of the same kind (a material type for a material type, ...), or a material's name.
      std::vector<std::string> choices;
      for (const auto& kind : word_kinds())
        if (std::find(kind.begin(), kind.end(), node.get<std::string>()) != kind.end()) choices = kind;
      if (scene.is_object() && scene.contains("materials") && scene["materials"].is_object())
        if (choices.empty() || pick(rng, 8) == 0)
          for (auto& [name, value] : scene["materials"].items()) choices.push_back(name);
      node = choices.empty() || pick(rng, 8) == 0 ? random_word(rng) : choices[pick(rng, choices.size())];
      break;
    }
    case Json::value_t::boolean:
      node = !node.get<bool>();
      break;
    case Json::value_t::array: {
      const bool numbers = !node.empty() && std::all_of(node.begin(), node.end(), [](const Json& e) { return e.is_number(); });
      if (numbers && pick(rng, 4)) {  // a vector (or index triple): every component at once, its length kept
        if (node[0].is_number_float()) {
          const double x = interesting_float(rng, node[0].get<double>());
          for (Json& e : node) e = pick(rng, 3) ? x : interesting_float(rng, e.get<double>());
        } else {
          const int64_t x = interesting_integer(rng, node[0].get<int64_t>());
          for (Json& e : node) e = pick(rng, 3) ? x : interesting_integer(rng, e.get<int64_t>());
        }
        break;
      }
      switch (node.empty() ? 2 : pick(rng, 4)) {
        case 0: node.erase(pick(rng, node.size())); break;
        case 1: node.push_back(node[pick(rng, node.size())]); break;
        case 2: node.push_back(random_value(rng, nodes)); break;
        default: std::swap(node[pick(rng, node.size())], node[pick(rng, node.size())]);
      }
      break;
    }
    case Json::value_t::object:
      if (!node.empty() && pick(rng, 3) == 0) {
        auto it = node.begin();
        std::advance(it, pick(rng, node.size()));
        const std::string key = it.key();
        node.erase(key);
      } else if (pick(rng, 4)) {  // a key and value of another object of the scene or the snippets
        std::vector<Json*> objects;
        for (Json* n : nodes)
          if (n->is_object() && !n->empty()) objects.push_back(n);
        collect(const_cast<Json&>(snippets()), objects);  // only read
        objects.erase(std::remove_if(objects.begin(), objects.end(), [](Json* n) { return !n->is_object() || n->empty(); }),
                      objects.end());
        if (objects.empty()) break;
        const Json& from = *objects[pick(rng, objects.size())];
        auto it = from.begin();
        std::advance(it, pick(rng, from.size()));
        const std::string key = it.key();
        const Json value = it.value();
        node[key] = value;
      } else {
        node[keys()[pick(rng, keys().size())]] = random_value(rng, nodes);
      }
      break;
    default:
      node = random_value(rng, nodes);
  }
}

// Where the text of the first file begins (after its separator line), or the size if there is none.
inline size_t files_begin(std::string_view input) {
  const size_t end = scene_end(input);
  if (end == input.size()) return end;
  const size_t line_end = input.find('\n', end + 1);
  return line_end == std::string_view::npos ? input.size() : line_end + 1;
}

// The scene of an input as JSON (discarded if it is not).
inline Json parse_scene(std::string_view input) {
  if (input.substr(0, 4) == "--- ") return Json(Json::value_t::discarded);  // no scene before the first file
  return Json::parse(input.substr(0, scene_end(input)), nullptr, /*allow_exceptions=*/false);
}

// The scene written out, then the files; 0 if it does not fit in max_size.
inline size_t write_input(const Json& scene, std::string_view files, uint8_t* out, size_t max_size) {
  std::string text;
  try {
    text = scene.dump();
  } catch (const Json::exception&) {
    return 0;  // a string that is not UTF-8 cannot be written
  }
  text += files;
  if (text.size() > max_size) return 0;
  std::memcpy(out, text.data(), text.size());
  return text.size();
}

// Every member of an object in j, named by its key ("[]" appended for the elements of an array member).
inline void collect_members(Json& j, const std::string& name, std::vector<std::pair<std::string, Json*>>& out) {
  if (!name.empty()) out.emplace_back(name, &j);
  if (j.is_object())
    for (auto& [key, value] : j.items()) collect_members(value, key, out);
  else if (j.is_array())
    for (Json& value : j) collect_members(value, name.empty() ? "" : name + "[]", out);
}

}  // namespace scene_mutator_detail

// Mutates the scene of the input in data (size bytes) in place; returns the new size, or 0 where the scene
// is not JSON or the result would not fit in max_size (then the caller mutates the bytes instead).
inline size_t mutate_scene(uint8_t* data, size_t size, size_t max_size, unsigned seed) {
  using namespace scene_mutator_detail;
  const std::string_view input(reinterpret_cast<const char*>(data), size);
  Json scene = parse_scene(input);
  if (scene.is_discarded()) return 0;
  Rng rng(seed);
  mutate_once(scene, rng);
  return write_input(scene, input.substr(scene_end(input)), data, max_size);
}

// The first file's separator line stays, so that a byte-level mutation of the files (with libFuzzer's
// LLVMFuzzerMutate, passed as mutate) leaves the scene as it is. 0 where the input has no file.
template <class Mutate>
size_t mutate_files(uint8_t* data, size_t size, size_t max_size, Mutate mutate) {
  using namespace scene_mutator_detail;
  const size_t begin = files_begin(std::string_view(reinterpret_cast<const char*>(data), size));
  if (begin >= size || begin >= max_size) return 0;
  return begin + mutate(data + begin, size - begin, max_size - begin);
}

// Crosses two inputs: a member of the second scene (a material, a shape, a camera, a colour, ...) replaces
// a member of the same name in the first, whose files are kept and joined by the second's. 0 where a
// scene is not JSON, no member matches or the result does not fit in max_size.
inline size_t cross_scenes(const uint8_t* data1, size_t size1, const uint8_t* data2, size_t size2, uint8_t* out,
                           size_t max_size, unsigned seed) {
  using namespace scene_mutator_detail;
  const std::string_view a(reinterpret_cast<const char*>(data1), size1), b(reinterpret_cast<const char*>(data2), size2);
  Json first = parse_scene(a), second = parse_scene(b);
  if (first.is_discarded() || second.is_discarded()) return 0;
  Rng rng(seed);
  std::vector<std::pair<std::string, Json*>> to, from;
  collect_members(first, "", to);
  collect_members(second, "", from);
  if (from.empty()) return 0;
  const auto& [name, value] = from[pick(rng, from.size())];
  std::vector<Json*> same;
  for (const auto& [n, v] : to)
    if (n == name) same.push_back(v);
  if (same.empty()) return 0;
  *same[pick(rng, same.size())] = *value;
  // The first input's files, then those of the second that the first lacks (a shape taken over may name
  // them).
  std::string files(a.substr(scene_end(a)));
  const std::vector<InputFile> mine = split_render_input(a), theirs = split_render_input(b);
  for (size_t i = 1; i < theirs.size(); ++i)
    if (std::none_of(mine.begin() + 1, mine.end(), [&](const InputFile& f) { return f.name == theirs[i].name; }))
      files += "\n--- " + theirs[i].name + "\n" + theirs[i].text;
  return write_input(first, files, out, max_size);
}

}  // namespace fuzz
