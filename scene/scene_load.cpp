// Reads the JSON scene file (docs/scene-format.md), checking every key and type, and loads, transforms
// and cleans the meshes it names.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <initializer_list>
#include <limits>
#include <map>
#include <optional>
#include <sstream>

#include <glm/geometric.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/mat3x3.hpp>
#include <glm/mat4x4.hpp>
#include <nlohmann/json.hpp>

#include "scene/scene_description.h"
#include "kernels/shared/types.h"
#include "scene/gltf_load.h"
#include "scene/mesh_subdivide.h"
#include "scene/mtl_load.h"
#include "scene/obj_load.h"
#include "scene/ply_stl_off_load.h"
#include "scene/input_file.h"
#include "scene/scene_error.h"
#include "scene/scene_import.h"
#include "scene/serialized_load.h"
#include "scene/scene_limits.h"
#include "scene/texture_load.h"

using nlohmann::json;

namespace {

// The smallest value a number that must be > 0 may have: float's smallest normal number.
constexpr double kSmallestPositive = std::numeric_limits<float>::min();

// A JSON value with its path in the file, so every error can say where it is.
struct Node {
  const std::string& file;
  const json& value;
  std::string path;
  // An imported scene's entries and their places in the source file (ImportedScene::origins).
  const std::vector<std::pair<std::string, std::string>>* origins = nullptr;

  // "FILE: JSON.PATH", the start of every message about this value; in an imported scene, the source
  // place of the entry that holds it first ("cbox.xml:34: shape \"obj\": shapes[3].radius").
  std::string place() const {
    if (const std::string* origin = source_place()) return *origin + ": " + path;
    return file + ": " + (path.empty() ? "(top level)" : path);
  }
  const std::string* source_place() const {
    if (!origins) return nullptr;
    const std::string* best = nullptr;
    size_t best_length = 0;
    for (const auto& [prefix, origin] : *origins) {
      bool holds = path.compare(0, prefix.size(), prefix) == 0 &&
                   (path.size() == prefix.size() || path[prefix.size()] == '.' || path[prefix.size()] == '[');
      if (holds && (!best || prefix.size() > best_length)) {
        best = &origin;
        best_length = prefix.size();
      }
    }
    return best;
  }
  [[noreturn]] void fail(const std::string& what) const { throw SceneError(place() + ": " + what); }
  Node at(const std::string& key) const {
    return {file, value.at(key), path.empty() ? key : path + "." + key, origins};
  }
  Node at(size_t i) const { return {file, value.at(i), path + "[" + std::to_string(i) + "]", origins}; }
  bool has(const std::string& key) const { return value.contains(key); }

  // Requires an object whose keys are all in `allowed` and that has every key in `required`.
  void expect_object(std::initializer_list<const char*> allowed,
                     std::initializer_list<const char*> required = {}) const {
    if (!value.is_object()) fail("expected an object");
    for (auto& [key, _] : value.items()) {
      bool known = false;
      for (const char* a : allowed) known = known || key == a;
      if (!known) fail("unknown key \"" + key + "\"");
    }
    for (const char* r : required)
      if (!value.contains(r)) fail(std::string("missing key \"") + r + "\"");
  }
  // The value as JSON writes it, for messages: ", got 1e-300".
  std::string got() const { return ", got " + value.dump(); }
  double number() const {
    if (!value.is_number()) fail("expected a number");
    double d = value.get<double>();
    // Colours and settings end up as floats, coordinates as floats relative to the camera: 1e39 would
    // become infinity there.
    if (!std::isfinite(d) || std::abs(d) > double(std::numeric_limits<float>::max()))
      fail("expected a finite number within float range" + got());
    return d;
  }
  double positive() const {
    double d = number();
    if (!(d > 0)) fail("expected a number > 0" + got());
    return d;
  }
  // A setting > 0 that is still > 0 as a float on the device: from float's smallest normal number on
  // (1.2e-38; below it a float is 0 or a denormal, which devices may flush to 0). Sizes of geometry
  // need only be > 0: degenerate geometry is handled (tests/robustness_test.cpp).
  double positive_setting() const {
    double d = positive();
    if (!(d >= kSmallestPositive)) fail("expected a number > 0 (at least 1.2e-38)" + got());
    return d;
  }
  // An integer in [lo, hi]. nlohmann keeps what the text says: 8 is an integer, 8.0 and 8e0 are not, and
  // are refused like 8.5 (docs/scene-format.md: counts are written as integers). The lower bound is
  // checked for every representation: a non-negative integer is parsed as unsigned.
  uint32_t count(uint32_t lo, uint32_t hi) const {
    const std::string expected = "expected an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]";
    if (!value.is_number()) fail(expected);
    if (!value.is_number_integer()) fail(expected + " without a fraction or exponent" + got());
    bool inside = value.is_number_unsigned() ? value.get<uint64_t>() >= lo && value.get<uint64_t>() <= hi
                                             : value.get<int64_t>() >= int64_t(lo) && value.get<int64_t>() <= int64_t(hi);
    if (!inside) fail(expected + got());
    return uint32_t(value.get<uint64_t>());
  }
  bool boolean() const {
    if (!value.is_boolean()) fail("expected true or false");
    return value.get<bool>();
  }
  std::string string() const {
    if (!value.is_string()) fail("expected a string");
    return value.get<std::string>();
  }
  glm::vec3 vec3() const {
    if (!value.is_array() || value.size() != 3) fail("expected an array of 3 numbers");
    return {float(at(0).number()), float(at(1).number()), float(at(2).number())};
  }
  // Positions, directions and transforms stay in double until the camera-relative flattening.
  glm::dvec3 dvec3() const {
    if (!value.is_array() || value.size() != 3) fail("expected an array of 3 numbers");
    return {at(0).number(), at(1).number(), at(2).number()};
  }
  glm::vec3 color() const {
    glm::vec3 c = vec3();
    if (c.x < 0 || c.y < 0 || c.z < 0) fail("expected non-negative values");
    return c;
  }
  // A light's colour: larger values overflow the film's sums of squares (scene/scene_limits.h).
  glm::vec3 light_color() const {
    glm::vec3 c = color();
    if (c.x > kMaxLightValue || c.y > kMaxLightValue || c.z > kMaxLightValue) fail("expected values of at most 1e12");
    return c;
  }
  std::vector<Node> array() const {
    if (!value.is_array()) fail("expected an array");
    std::vector<Node> items;
    for (size_t i = 0; i < value.size(); ++i) items.push_back(at(i));
    return items;
  }
};

// Finite and within float range: what can still become a float relative to a camera in float range.
bool within_float_range(const glm::dvec3& p) {
  const double max = std::numeric_limits<float>::max();
  return std::abs(p.x) <= max && std::abs(p.y) <= max && std::abs(p.z) <= max;
}

uint32_t read_filter(const Node& n, CameraDesc& c) {
  n.expect_object({"type", "radius", "sigma"}, {"type"});
  std::string type = n.at("type").string();
  if (type == "box") {
    if (n.has("radius") || n.has("sigma")) n.fail("a box filter covers its pixel and takes no radius or sigma");
    return PC_FILTER_BOX;
  }
  // In pixels, at most kMaxFilterRadius: for sigma, its default radius 3 sigma too.
  auto pixels = [](const Node& v, double largest) {
    double d = v.positive_setting();
    if (d > largest) v.fail("expected at most " + std::to_string(int(largest)) + " pixels" + v.got());
    return float(d);
  };
  if (type == "tent") {
    if (n.has("sigma")) n.at("sigma").fail("a tent filter takes no sigma");
    c.filter_radius = n.has("radius") ? pixels(n.at("radius"), kMaxFilterRadius) : 1.0f;
    return PC_FILTER_TENT;
  }
  if (type == "gaussian") {
    c.filter_sigma = n.has("sigma") ? pixels(n.at("sigma"), kMaxFilterRadius / 3) : 0.5f;
    c.filter_radius = n.has("radius") ? pixels(n.at("radius"), kMaxFilterRadius) : 3 * c.filter_sigma;
    return PC_FILTER_GAUSSIAN;
  }
  n.at("type").fail("unknown filter \"" + type + "\" (expected box, tent or gaussian)");
}

CameraDesc read_camera(const Node& n) {
  n.expect_object({"type", "position", "look_at", "up", "fov_y_degrees", "width", "height", "aperture_radius",
                   "focus_distance", "filter", "handedness"},
                  {"position", "look_at", "width", "height"});
  std::string type = n.has("type") ? n.at("type").string() : "perspective";
  if (type != "perspective" && type != "thin_lens")
    n.at("type").fail("unknown camera type \"" + type + "\" (expected perspective or thin_lens)");
  CameraDesc c;
  c.position = n.at("position").dvec3();
  c.look_at = n.at("look_at").dvec3();
  if (n.has("up")) c.up = n.at("up").dvec3();
  if (n.has("handedness")) {
    const std::string h = n.at("handedness").string();
    if (h != "right" && h != "left") n.at("handedness").fail("expected \"right\" or \"left\", got \"" + h + "\"");
    c.left_handed = h == "left";
  }
  if (n.has("fov_y_degrees")) {
    c.fov_y_degrees = n.at("fov_y_degrees").positive_setting();
    if (c.fov_y_degrees >= 180) n.at("fov_y_degrees").fail("expected a field of view below 180 degrees");
  }
  c.width = n.at("width").count(1, kMaxFilmSide);
  c.height = n.at("height").count(1, kMaxFilmSide);
  glm::dvec3 forward = c.look_at - c.position;
  if (glm::length(forward) == 0) n.fail("position and look_at coincide");
  if (glm::length(glm::cross(forward, c.up)) == 0)
    (n.has("up") ? n.at("up") : n).fail("up is parallel to the view direction (set camera.up)");
  if (type == "thin_lens") {
    if (!n.has("aperture_radius") || !n.has("focus_distance"))
      n.fail("a thin_lens camera needs aperture_radius and focus_distance");
    // The lens and the plane in focus lie within the reach of the scene's geometry (kMaxSceneExtent):
    // farther, squared distances from the ray origins would overflow float.
    Node aperture = n.at("aperture_radius"), focus = n.at("focus_distance");
    double a = aperture.number();
    if (!(a >= 0)) aperture.fail("expected a number >= 0" + aperture.got());
    if (a > kMaxSceneExtent) aperture.fail("expected at most 1.5e18" + aperture.got());
    c.aperture_radius = float(a);
    c.focus_distance = float(focus.positive_setting());
    if (c.focus_distance > kMaxSceneExtent) focus.fail("expected at most 1.5e18" + focus.got());
  } else if (n.has("aperture_radius") || n.has("focus_distance")) {
    n.fail("aperture_radius and focus_distance need \"type\": \"thin_lens\"");
  }
  if (n.has("filter")) c.filter = read_filter(n.at("filter"), c);
  return c;
}

// A colour in [0, 1] per channel.
glm::vec3 read_albedo(const Node& n) {
  glm::vec3 c = n.color();
  if (c.x > 1 || c.y > 1 || c.z > 1) n.fail("expected values in [0, 1]");
  return c;
}

// GGX roughness in [0.01, 1] (0 allowed where smooth is meant); alpha = roughness^2.
float read_roughness(const Node& n, bool allow_smooth) {
  double r = n.number();
  if (allow_smooth && r == 0) return 0;
  if (!(r >= 0.01 && r <= 1))
    n.fail(allow_smooth ? "expected 0 (smooth) or a roughness in [0.01, 1]"
                        : "expected a roughness in [0.01, 1] (a smooth metal is a mirror)");
  return float(r * r);
}

float read_ior(const Node& n) {
  double ior = n.number();
  if (!(ior >= kSmallestPositive && ior <= 10)) n.fail("expected an index of refraction in (0, 10]" + n.got());
  return float(ior);
}

// Loads an image file once per file, wrap mode and use; returns its index in scene.textures. A
// reflectance texture (a material colour) has its texels clamped to [0, 1], with a warning when that
// changes any: a surface reflecting more than it receives would create energy. `where` starts messages.
// `load` decodes the image named `file` (a file, or an image embedded in a glTF file) when no texture of
// that name, wrap and use is loaded yet.
uint32_t add_texture_image(SceneDescription& scene, const std::string& file, const std::function<TextureImage()>& load,
                           const std::string& where, uint32_t wrap, bool reflectance) {
  for (uint32_t i = 0; i < scene.textures.size(); ++i) {
    const TextureImage& t = scene.textures[i];
    if (t.file == file && t.wrap == wrap && t.reflectance == reflectance) return i;
  }
  TextureImage image;
  try {
    image = load();
  } catch (const SceneError& e) {
    throw SceneError(where + ": " + e.what());
  }
  uint64_t words = image.words.size();
  for (const TextureImage& t : scene.textures) words += t.words.size();
  if (words > kMaxSceneTexelWords)
    throw SceneError(where + ": " + file + ": the scene's textures would take " + std::to_string(words) +
                     " words of texels, more than the largest of " + std::to_string(kMaxSceneTexelWords) +
                     " (texel word indices are 32-bit on the device)");
  image.wrap = wrap;
  image.reflectance = reflectance;
  if (reflectance) {
    size_t clamped = clamp_texels_to_one(image);
    if (clamped > 0)
      scene.warnings.push_back(where + ": " + file + ": " + std::to_string(clamped) +
                               " texels above 1 clamped to 1 (a reflectance above 1 would create energy)");
  }
  scene.textures.push_back(std::move(image));
  return uint32_t(scene.textures.size() - 1);
}

uint32_t add_texture_file(SceneDescription& scene, const std::string& file, const std::string& where, uint32_t wrap,
                          bool reflectance) {
  return add_texture_image(scene, file, [&] { return load_texture_image(file); }, where, wrap, reflectance);
}

// Loads the image file named by n (relative to the scene's directory).
uint32_t add_texture(SceneDescription& scene, const Node& n, const std::filesystem::path& dir, uint32_t wrap,
                     bool reflectance) {
  return add_texture_file(scene, (dir / n.string()).string(), n.place(), wrap, reflectance);
}

// The largest texel value per channel.
glm::vec3 texture_max(const TextureImage& t) {
  glm::vec3 m(0);
  for (size_t i = 0, n = size_t(t.width) * t.height; i < n; ++i) m = glm::max(m, texel_linear(t, i));
  return m;
}

// The "wrap" of a texture object: repeat (the default), clamp or mirror.
uint32_t read_wrap(const Node& n) {
  if (!n.has("wrap")) return PC_WRAP_REPEAT;
  std::string w = n.at("wrap").string();
  if (w == "clamp") return PC_WRAP_CLAMP;
  if (w == "mirror") return PC_WRAP_MIRROR;
  if (w != "repeat") n.at("wrap").fail("unknown wrap mode \"" + w + "\" (expected repeat, clamp or mirror)");
  return PC_WRAP_REPEAT;
}

// [a, b], each a number > 0 (positive) or any finite number.
glm::vec2 read_pair(const Node& n, bool positive) {
  if (!n.value.is_array() || n.value.size() != 2) n.fail("expected an array of 2 numbers");
  glm::vec2 v;
  for (size_t i = 0; i < 2; ++i) v[int(i)] = float(positive ? n.at(i).positive_setting() : n.at(i).number());
  return v;
}

// {"checkerboard": {"color0": [r, g, b], "color1": [r, g, b], "tiles": [nu, nv], "offset": [ou, ov]}}:
// Mitsuba's checkerboard (its colours 0.4 and 0.2 by default, 2 tiles per unit of u and v), evaluated at the
// point (scene/texture_load.h). Its colours are in [0, 1], as a material colour's or an opacity's.
uint32_t add_checkerboard(SceneDescription& scene, const Node& n) {
  n.expect_object({"checkerboard"}, {"checkerboard"});
  const Node c = n.at("checkerboard");
  c.expect_object({"color0", "color1", "tiles", "offset"});
  glm::vec3 color0 = c.has("color0") ? read_albedo(c.at("color0")) : glm::vec3(0.4f);
  glm::vec3 color1 = c.has("color1") ? read_albedo(c.at("color1")) : glm::vec3(0.2f);
  glm::vec2 tiles = c.has("tiles") ? read_pair(c.at("tiles"), true) : glm::vec2(2);
  glm::vec2 offset = c.has("offset") ? read_pair(c.at("offset"), false) : glm::vec2(0);
  TextureImage image = checkerboard_texture(color0, color1, tiles, offset);
  const std::string name = image.file;
  return add_texture_image(scene, name, [&] { return std::move(image); }, c.place(), PC_WRAP_REPEAT, true);
}

// An image ({"texture": FILE, "wrap": ...}) or a checkerboard ({"checkerboard": {...}}) where a material
// takes a texture; `expected` says what else the value may be, for messages.
uint32_t add_material_texture(const Node& n, SceneDescription& scene, const std::filesystem::path& dir,
                              const std::string& expected) {
  if (!n.value.is_object())
    n.fail("expected " + expected + " or {\"texture\": FILE} or {\"checkerboard\": {...}}");
  if (n.has("checkerboard")) return add_checkerboard(scene, n);
  n.expect_object({"texture", "wrap"}, {"texture"});
  return add_texture(scene, n.at("texture"), dir, read_wrap(n), true);
}

// A material colour: [r, g, b] in [0, 1], {"texture": FILE, "wrap": "repeat" | "clamp" | "mirror"} or
// {"checkerboard": {...}}. Sets m.color (1 for a texture, which the colour then is) and m.color_texture.
void read_albedo_or_texture(const Node& n, SceneDescription& scene, const std::filesystem::path& dir,
                            MaterialDesc& m) {
  if (n.value.is_array()) {
    m.color = read_albedo(n);
    return;
  }
  m.color_texture = add_material_texture(n, scene, dir, "an array of 3 numbers");
  m.color = glm::vec3(1);
}

// A material's opacity (cut-outs): a number in [0, 1], or {"texture": FILE, "wrap": ...} (an opacity map), or
// {"checkerboard": {...}} (its red channel).
void read_opacity(const Node& n, SceneDescription& scene, const std::filesystem::path& dir, MaterialDesc& m) {
  if (n.value.is_number()) {
    double o = n.number();
    if (!(o >= 0 && o <= 1)) n.fail("expected a number in [0, 1]" + n.got());
    m.opacity = float(o);
    return;
  }
  m.opacity_texture = add_material_texture(n, scene, dir, "a number in [0, 1]");
}

MaterialDesc read_material(const Node& n, const std::string& name, SceneDescription& scene,
                           const std::filesystem::path& dir) {
  if (!n.value.is_object() || !n.has("type")) n.fail("expected an object with a \"type\"");
  MaterialDesc m;
  m.name = name;
  m.type = n.at("type").string();
  if (n.has("opacity")) read_opacity(n.at("opacity"), scene, dir, m);
  if (m.type == "diffuse") {
    n.expect_object({"type", "opacity", "reflectance"});
    m.type_id = PC_MAT_DIFFUSE;
    if (n.has("reflectance")) read_albedo_or_texture(n.at("reflectance"), scene, dir, m);
  } else if (m.type == "oren_nayar") {
    n.expect_object({"type", "opacity", "reflectance", "sigma_degrees"}, {"sigma_degrees"});
    m.type_id = PC_MAT_OREN_NAYAR;
    if (n.has("reflectance")) read_albedo_or_texture(n.at("reflectance"), scene, dir, m);
    double sigma = n.at("sigma_degrees").number();
    if (!(sigma >= 0 && sigma <= 90)) n.at("sigma_degrees").fail("expected an angle in [0, 90] degrees");
    m.sigma = float(sigma * M_PI / 180);
  } else if (m.type == "phong") {
    n.expect_object({"type", "opacity", "diffuse", "specular", "exponent"}, {"exponent"});
    m.type_id = PC_MAT_PHONG;
    m.color = glm::vec3(0);
    if (n.has("diffuse")) read_albedo_or_texture(n.at("diffuse"), scene, dir, m);
    m.specular = n.has("specular") ? read_albedo(n.at("specular")) : glm::vec3(0);
    double e = n.at("exponent").number();
    if (!(e >= kSmallestPositive && e <= 1e5)) n.at("exponent").fail("expected an exponent in (0, 100000]" + n.at("exponent").got());
    m.exponent = float(e);
    bool textured = m.color_texture != PC_INVALID;
    glm::vec3 sum = (textured ? texture_max(scene.textures[m.color_texture]) : m.color) + m.specular;
    if (sum.x > 1 || sum.y > 1 || sum.z > 1)
      n.fail(std::string(textured ? "the diffuse texture's largest value" : "diffuse") +
             " + specular exceeds 1 (the surface would create energy)");
  } else if (m.type == "mirror") {
    n.expect_object({"type", "opacity", "reflectance", "eta", "k"});
    m.type_id = PC_MAT_MIRROR;
    m.color = glm::vec3(1);
    if (n.has("reflectance")) read_albedo_or_texture(n.at("reflectance"), scene, dir, m);
    if (n.has("eta") || n.has("k")) {  // a smooth metal: the reflectance times its Fresnel term
      if (!n.has("eta") || !n.has("k")) n.fail("a metal mirror needs both eta and k");
      m.specular = n.at("eta").color();
      m.k = n.at("k").color();
    }
  } else if (m.type == "dielectric" || m.type == "thin_dielectric") {
    n.expect_object({"type", "opacity", "ior", "transmittance"}, {"ior"});
    m.type_id = m.type == "dielectric" ? PC_MAT_DIELECTRIC : PC_MAT_THIN_DIELECTRIC;
    m.ior = read_ior(n.at("ior"));
    m.color = glm::vec3(1);
    if (n.has("transmittance")) read_albedo_or_texture(n.at("transmittance"), scene, dir, m);
  } else if (m.type == "rough_conductor") {
    n.expect_object({"type", "opacity", "roughness", "eta", "k", "specular"}, {"roughness"});
    m.type_id = PC_MAT_ROUGH_CONDUCTOR;
    m.alpha = read_roughness(n.at("roughness"), false);
    if (n.has("specular")) {
      if (n.has("eta") || n.has("k")) n.fail("give either specular or eta and k");
      set_conductor_reflectance(m, read_albedo(n.at("specular")));
    } else {
      if (!n.has("eta") || !n.has("k")) n.fail("a rough_conductor needs specular, or eta and k");
      m.specular = n.at("eta").vec3();
      m.k = n.at("k").color();
      if (m.specular.x <= 0 || m.specular.y <= 0 || m.specular.z <= 0) n.at("eta").fail("expected values > 0");
    }
  } else if (m.type == "plastic") {
    n.expect_object({"type", "opacity", "diffuse", "ior", "roughness"});
    m.type_id = PC_MAT_PLASTIC;
    if (n.has("diffuse")) read_albedo_or_texture(n.at("diffuse"), scene, dir, m);
    if (n.has("ior")) m.ior = read_ior(n.at("ior"));
    if (n.has("roughness")) m.alpha = read_roughness(n.at("roughness"), true);
  } else {
    n.at("type").fail("unknown material type \"" + m.type +
                      "\" (expected diffuse, oren_nayar, phong, mirror, dielectric, thin_dielectric, rough_conductor or plastic)");
  }
  return m;
}

// Normalised in double: in float, [3e38, 3e38, 0] has an infinite length and [1e-30, 0, 0] a zero one.
glm::vec3 read_unit_direction(const Node& n) {
  glm::dvec3 d = n.dvec3();
  if (glm::length(d) == 0) n.fail("expected a non-zero direction");
  return glm::vec3(glm::normalize(d));
}

glm::dmat4 read_transform(const Node& n);

// An environment's transform: a rotation only (orthonormal within 1e-5, not mirroring, no translation),
// which places the map: a world direction looks it up at the direction the rotation takes there.
glm::dmat3 read_rotation(const Node& n) {
  const glm::dmat4 m = read_transform(n);
  const glm::dmat3 r(m);
  const glm::dmat3 error = glm::transpose(r) * r - glm::dmat3(1.0);
  double largest = 0;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) largest = std::max(largest, std::abs(error[i][j]));
  if (m[3] != glm::dvec4(0, 0, 0, 1) || largest > 1e-5 || glm::determinant(r) < 0)
    n.fail("an environment's transform may only rotate (no translation, scale, shear or mirroring)");
  return r;
}

LightDesc read_light(const Node& n) {
  if (!n.value.is_object() || !n.has("type")) n.fail("expected an object with a \"type\"");
  std::string type = n.at("type").string();
  LightDesc l;
  l.label = n.path;
  if (type == "point") {
    n.expect_object({"type", "position", "intensity"}, {"position", "intensity"});
    l.type = PC_LIGHT_POINT;
    l.position = n.at("position").dvec3();
    l.emission = n.at("intensity").light_color();
  } else if (type == "spot") {
    n.expect_object({"type", "position", "direction", "intensity", "outer_angle_degrees", "inner_angle_degrees"},
                    {"position", "direction", "intensity", "outer_angle_degrees"});
    l.type = PC_LIGHT_SPOT;
    l.position = n.at("position").dvec3();
    l.direction = read_unit_direction(n.at("direction"));
    l.emission = n.at("intensity").light_color();
    double outer = n.at("outer_angle_degrees").number();
    if (!(outer >= kSmallestPositive && outer <= 180))
      n.at("outer_angle_degrees").fail("expected an angle in (0, 180] degrees" + n.at("outer_angle_degrees").got());
    double inner = n.has("inner_angle_degrees") ? n.at("inner_angle_degrees").number() : outer;
    if (!(inner >= 0 && inner <= outer))
      n.at("inner_angle_degrees").fail("expected an angle in [0, outer_angle_degrees]" + n.at("inner_angle_degrees").got());
    l.cos_outer = float(std::cos(outer * M_PI / 180));
    l.cos_inner = float(std::cos(inner * M_PI / 180));
  } else if (type == "directional") {
    n.expect_object({"type", "direction", "irradiance"}, {"direction", "irradiance"});
    l.type = PC_LIGHT_DIRECTIONAL;
    l.direction = read_unit_direction(n.at("direction"));
    l.emission = n.at("irradiance").light_color();
  } else if (type == "environment") {
    n.expect_object({"type", "radiance", "file", "scale", "transform", "mapping", "filter"});
    l.type = PC_LIGHT_ENVIRONMENT;
    if (n.has("transform")) l.rotation = read_rotation(n.at("transform"));
    if (n.has("radiance") == n.has("file")) n.fail("an environment light needs either radiance or file");
    if (n.has("radiance")) {
      for (const char* key : {"scale", "mapping", "filter"})
        if (n.has(key)) n.at(key).fail(std::string(key) + " goes with file");
      l.emission = n.at("radiance").light_color();
    } else {
      // The map's parameterisation: lat-long (the default), or pbrt-v4's equal-area octahedral square,
      // looked up bilinearly (the default) or at the nearest texel as pbrt-v4 does (kernels/environment.cl).
      std::string mapping = n.has("mapping") ? n.at("mapping").string() : "lat_long";
      std::string filter = n.has("filter") ? n.at("filter").string() : "bilinear";
      if (mapping != "lat_long" && mapping != "equal_area")
        n.at("mapping").fail("unknown mapping \"" + mapping + "\" (expected lat_long or equal_area)");
      if (filter != "bilinear" && filter != "nearest")
        n.at("filter").fail("unknown filter \"" + filter + "\" (expected bilinear or nearest)");
      if (mapping == "lat_long" && filter != "bilinear")
        n.at("filter").fail("a lat_long map is looked up bilinearly (filter nearest is for equal_area maps)");
      if (mapping == "equal_area") l.mapping = filter == "nearest" ? PC_ENV_EQUAL_AREA_NEAREST : PC_ENV_EQUAL_AREA;
      l.emission = glm::vec3(n.has("scale") ? float(n.at("scale").number()) : 1.0f);
      if (!(l.emission.x >= 0 && l.emission.x <= kMaxLightValue))
        n.at("scale").fail("expected a number in [0, 1e12]" + n.at("scale").got());
    }
  } else {
    n.at("type").fail("unknown light type \"" + type + "\" (expected point, spot, directional or environment)");
  }
  return l;
}

// Reads "transform": {"matrix": 4x4 rows} or any of {"translate", "rotate", "scale"}, applied as
// scale, then rotate, then translate. Composed and applied in double: a translation by 1e6 composed in
// float would already move the shape by up to 0.03.
glm::dmat4 read_transform(const Node& n) {
  n.expect_object({"translate", "rotate", "scale", "matrix"});
  if (n.has("matrix")) {
    if (n.has("translate") || n.has("rotate") || n.has("scale"))
      n.fail("\"matrix\" cannot be combined with translate, rotate or scale");
    Node m = n.at("matrix");
    if (!m.value.is_array() || m.value.size() != 4) m.fail("expected 4 rows of 4 numbers");
    glm::dmat4 result(1.0);
    for (int r = 0; r < 4; ++r) {
      Node row = m.at(r);
      if (!row.value.is_array() || row.value.size() != 4) row.fail("expected 4 numbers");
      for (int c = 0; c < 4; ++c) result[c][r] = row.at(c).number();  // glm is column-major
    }
    if (result[0][3] != 0 || result[1][3] != 0 || result[2][3] != 0 || result[3][3] != 1)
      m.fail("expected an affine matrix (last row 0 0 0 1)");
    if (glm::determinant(glm::dmat3(result)) == 0) m.fail("the matrix is singular");
    return result;
  }
  glm::dmat4 t(1.0);
  if (n.has("translate")) t = glm::translate(t, n.at("translate").dvec3());
  if (n.has("rotate")) {
    Node r = n.at("rotate");
    r.expect_object({"axis", "degrees"}, {"axis", "degrees"});
    glm::dvec3 axis = r.at("axis").dvec3();
    if (glm::length(axis) == 0) r.at("axis").fail("expected a non-zero axis");
    t = glm::rotate(t, glm::radians(r.at("degrees").number()), glm::normalize(axis));
  }
  if (n.has("scale")) {
    Node s = n.at("scale");
    glm::dvec3 v = s.value.is_array() ? s.dvec3() : glm::dvec3(s.number());
    if (v.x == 0 || v.y == 0 || v.z == 0) s.fail("expected non-zero scale factors");
    t = glm::scale(t, v);
  }
  return t;
}

// The first camera of a glTF file: "camera": {"from_gltf": FILE, "transform": ..., "width", "height",
// "filter"}. The transform places it as a gltf shape's places the file's geometry.
CameraDesc read_gltf_camera(const Node& n, const std::filesystem::path& dir, std::vector<std::string>& warnings) {
  n.expect_object({"from_gltf", "transform", "width", "height", "filter"}, {"from_gltf", "width", "height"});
  const std::string file = (dir / n.at("from_gltf").string()).string();
  GltfScene gltf;
  try {
    gltf = load_gltf(file, warnings);
  } catch (const SceneError& e) {
    n.at("from_gltf").fail(e.what());
  }
  if (!gltf.camera.present) n.at("from_gltf").fail(file + ": no node of its scene has a camera");
  if (!gltf.camera.perspective) n.at("from_gltf").fail(gltf.camera.where + ": orthographic cameras are not supported");
  const glm::dmat4 transform = n.has("transform") ? read_transform(n.at("transform")) : glm::dmat4(1.0);
  CameraDesc c;
  c.width = n.at("width").count(1, kMaxFilmSide);
  c.height = n.at("height").count(1, kMaxFilmSide);
  c.position = glm::dvec3(transform * glm::dvec4(gltf.camera.position, 1.0));
  glm::dvec3 forward = glm::dmat3(transform) * gltf.camera.forward;
  c.up = glm::dmat3(transform) * gltf.camera.up;
  if (!(glm::length(forward) > 0) || !(glm::length(glm::cross(forward, c.up)) > 0) || !within_float_range(c.position))
    n.at("from_gltf").fail(gltf.camera.where + ": its transform leaves the camera no position or view direction");
  c.look_at = c.position + glm::normalize(forward);
  c.aimed = false;
  const double degrees = gltf.camera.yfov_radians * 180 / M_PI;
  if (!(degrees >= kSmallestPositive && degrees < 180))
    n.at("from_gltf").fail(gltf.camera.where + ": yfov " + std::to_string(gltf.camera.yfov_radians) +
                           " radians, expected a field of view in (0, pi)");
  c.fov_y_degrees = float(degrees);
  // The vertical field of view is kept; the horizontal one follows from the film, as for pathcl's camera.
  const double aspect = double(c.width) / c.height;
  if (gltf.camera.aspect_ratio > 0 && std::abs(gltf.camera.aspect_ratio - aspect) > 1e-3 * aspect)
    warnings.push_back(n.place() + ": the film's aspect ratio " + std::to_string(aspect) + " differs from the camera's " +
                       std::to_string(gltf.camera.aspect_ratio) + " (" + gltf.camera.where +
                       "): its vertical field of view is kept");
  if (n.has("filter")) c.filter = read_filter(n.at("filter"), c);
  return c;
}

// Validates the soup's indices and coordinates (OBJ files are checked line by line in load_obj). `uvs`
// and `colors` (optional): one [u, v] / linear [r, g, b] in [0, 1] per position, which every corner at that
// position gets.
void check_inline_triangles(const Node& positions, const Node& indices, const Node* uvs, const Node* colors,
                            PolygonSoup& soup) {
  for (const Node& p : positions.array()) soup.positions.push_back(p.dvec3());
  std::vector<glm::vec2> vertex_uvs;
  if (uvs) {
    for (const Node& uv : uvs->array()) {
      if (!uv.value.is_array() || uv.value.size() != 2) uv.fail("expected an array of 2 numbers");
      vertex_uvs.push_back({float(uv.at(0).number()), float(uv.at(1).number())});
    }
    if (vertex_uvs.size() != soup.positions.size())
      uvs->fail("expected one [u, v] per position (" + std::to_string(soup.positions.size()) + "), got " +
                std::to_string(vertex_uvs.size()));
  }
  std::vector<glm::vec3> vertex_colors;
  if (colors) {
    for (const Node& c : colors->array()) {
      glm::vec3 color = c.color();
      if (color.x > 1 || color.y > 1 || color.z > 1) c.fail("expected values in [0, 1] (a colour multiplies the material's)");
      vertex_colors.push_back(color);
    }
    if (vertex_colors.size() != soup.positions.size())
      colors->fail("expected one [r, g, b] per position (" + std::to_string(soup.positions.size()) + "), got " +
                   std::to_string(vertex_colors.size()));
  }
  for (const Node& f : indices.array()) {
    if (!f.value.is_array() || f.value.size() != 3) f.fail("expected 3 vertex indices");
    std::vector<uint32_t> poly;
    for (int k = 0; k < 3; ++k) {
      Node i = f.at(k);
      if (!i.value.is_number_integer()) i.fail("expected an integer vertex index" + (i.value.is_number() ? i.got() : ""));
      // Unsigned when >= 0 (nlohmann), so that 2^64 - 1 is not read as -1.
      if (!i.value.is_number_unsigned() || i.value.get<uint64_t>() >= soup.positions.size())
        i.fail("vertex index " + i.value.dump() + " out of range (" + std::to_string(soup.positions.size()) +
               " positions)");
      poly.push_back(uint32_t(i.value.get<uint64_t>()));
    }
    if (uvs) soup.uvs.push_back({vertex_uvs[poly[0]], vertex_uvs[poly[1]], vertex_uvs[poly[2]]});
    if (colors) soup.colors.push_back({vertex_colors[poly[0]], vertex_colors[poly[1]], vertex_colors[poly[2]]});
    soup.polygons.push_back(poly);
  }
}

// The place of a shape's transform in messages (the shape itself when it has none).
Node transform_node(const Node& n) { return n.has("transform") ? n.at("transform") : n; }

// Applies a shape's transform to its soup, in double: positions, normals (by the inverse transpose) and,
// for a mirroring transform, the winding.
void place_soup(PolygonSoup& soup, const glm::dmat4& transform, const Node& n) {
  for (glm::dvec3& p : soup.positions) {
    p = glm::dvec3(transform * glm::dvec4(p, 1.0));
    if (!within_float_range(p))
      transform_node(n).fail("the transform takes a vertex to infinity");
  }
  // Normals take the inverse transpose, so that they stay perpendicular to the surface under non-uniform
  // scale; normalized in double (clean_mesh normalizes again), a zero normal stays zero.
  const glm::dmat3 normal_matrix = glm::transpose(glm::inverse(glm::dmat3(transform)));
  for (std::vector<glm::vec3>& corners : soup.normals)
    for (glm::vec3& normal : corners) {
      glm::dvec3 m = normal_matrix * glm::dvec3(normal);
      double length = glm::length(m);
      normal = length > 0 && std::isfinite(length) ? glm::vec3(m / length) : glm::vec3(0);
    }
  // A mirroring transform turns counter-clockwise into clockwise: swap winding so the front stays the front.
  if (glm::determinant(glm::dmat3(transform)) < 0) {
    for (auto& poly : soup.polygons) std::reverse(poly.begin(), poly.end());
    for (auto& uvs : soup.uvs) std::reverse(uvs.begin(), uvs.end());
    for (auto& normals : soup.normals) std::reverse(normals.begin(), normals.end());
    for (auto& colors : soup.colors) std::reverse(colors.begin(), colors.end());
  }
}

// An instance's placement: the corners of its mesh's bounding box (which contain every placed vertex)
// within float range. The box is the mesh's own (set_bounds), computed once for all its placements.
void check_placement(const InstancedMesh& m, const glm::dmat4& transform, const Node& n) {
  const glm::dvec3 &lo = m.lo, &hi = m.hi;
  for (int corner = 0; corner < 8; ++corner) {
    glm::dvec3 c(corner & 1 ? hi.x : lo.x, corner & 2 ? hi.y : lo.y, corner & 4 ? hi.z : lo.z);
    if (!within_float_range(glm::dvec3(transform * glm::dvec4(c, 1.0))))
      transform_node(n).fail("the transform takes a vertex to infinity");
  }
}

// "material": "from_mtl": the OBJ's MTL materials with ids in `used` become scene materials (in the
// order of first use); returns the scene material and the emission per MTL material id.
void add_mtl_materials(const ObjFile& obj, const std::vector<uint32_t>& used, SceneDescription& scene,
                       std::vector<uint32_t>& scene_material, std::vector<glm::vec3>& emission) {
  scene_material.assign(obj.materials.size(), PC_INVALID);
  emission.assign(obj.materials.size(), glm::vec3(0));
  for (uint32_t id : used) {
    if (scene_material[id] != PC_INVALID) continue;
    const MtlMaterial& mtl = obj.materials[id];
    MaterialDesc m = mtl.material;
    glm::vec3 diffuse_max = m.color;
    if (!mtl.opacity_texture.empty())
      m.opacity_texture =
          add_texture_file(scene, mtl.opacity_texture, mtl.opacity_texture_where + ": map_d", mtl.opacity_texture_wrap, true);
    if (!mtl.texture.empty()) {
      m.color_texture = add_texture_file(scene, mtl.texture, mtl.texture_where + ": map_Kd", mtl.texture_wrap, true);
      diffuse_max *= texture_max(scene.textures[m.color_texture]);
    }
    if (m.type_id == PC_MAT_PHONG) limit_phong_energy(m, diffuse_max, mtl.where, scene.warnings);
    scene_material[id] = uint32_t(scene.materials.size());
    emission[id] = mtl.emission;
    scene.materials.push_back(m);
  }
}

// The key under which shapes placing the same mesh are one instanced mesh: the shape's JSON without its
// transform; "" for a shape that is never instanced (a sphere, a glTF file, an emitter).
std::string instance_key(const Node& n) {
  if (!n.value.is_object() || !n.has("type") || n.has("emission")) return "";
  const auto& type = n.at("type").value;
  if (type != "mesh" && type != "triangles") return "";
  auto copy = n.value;
  copy.erase("transform");
  return copy.dump();
}

// A shape as the file describes it, placed by its transform; but a mesh that `placements` shapes place
// and that is to be instanced (see load_scene) in its own coordinates, with its transform, and
// *own_coordinates set.
ShapeDesc read_shape(const Node& n, const std::filesystem::path& dir, const std::map<std::string, uint32_t>& materials,
                     SceneDescription& scene, size_t placements, bool* own_coordinates) {
  *own_coordinates = false;
  if (!n.value.is_object() || !n.has("type")) n.fail("expected an object with a \"type\"");
  std::string type = n.at("type").string();
  ShapeDesc s;
  if (type == "mesh")
    n.expect_object({"type", "file", "material", "emission", "two_sided", "transform", "orient", "smooth",
                     "smooth_angle_degrees", "instance", "vertex_colors", "shape_index", "subdivide"},
                    {"file", "material"});
  else if (type == "triangles")
    n.expect_object({"type", "positions", "indices", "uvs", "colors", "material", "emission", "two_sided",
                     "transform", "orient", "smooth", "smooth_angle_degrees", "instance", "vertex_colors", "subdivide"},
                    {"positions", "indices", "material"});
  else if (type == "sphere")
    n.expect_object({"type", "center", "radius", "material", "emission", "two_sided", "transform",
                     "flip_normals"},
                    {"radius", "material"});
  else
    n.at("type").fail("unknown shape type \"" + type + "\" (expected mesh, triangles, sphere or gltf)");

  std::string material = n.at("material").string();
  const bool from_mtl = material == "from_mtl";
  if (from_mtl) {
    if (type != "mesh") n.at("material").fail("\"from_mtl\" needs a mesh shape (an OBJ file with mtllib)");
    if (n.has("emission")) n.at("emission").fail("with \"from_mtl\" the emission comes from the MTL files (Ke)");
  } else {
    auto it = materials.find(material);
    if (it == materials.end()) n.at("material").fail("unknown material \"" + material + "\"");
    s.material = it->second;
  }
  if (n.has("emission")) s.emission = n.at("emission").light_color();
  if (n.has("instance") && n.at("instance").boolean() && n.has("emission"))
    n.at("instance").fail("an emitter is not instanced (lights are sampled in world coordinates)");
  if (n.has("two_sided")) s.two_sided = n.at("two_sided").boolean();
  glm::dmat4 transform = n.has("transform") ? read_transform(n.at("transform")) : glm::dmat4(1.0);
  s.label = n.path;

  if (type == "sphere") {
    s.is_sphere = true;
    glm::dvec3 center = n.has("center") ? n.at("center").dvec3() : glm::dvec3(0);
    double radius = n.at("radius").positive();
    if (n.has("flip_normals")) s.flip_normals = n.at("flip_normals").boolean();
    // A sphere stays a sphere only under translation, rotation and uniform scale.
    glm::dmat3 l(transform);
    double sx = glm::length(l[0]), sy = glm::length(l[1]), sz = glm::length(l[2]);
    double tol = 1e-5 * std::max({sx, sy, sz});
    if (std::abs(sx - sy) > tol || std::abs(sx - sz) > tol || std::abs(glm::dot(l[0], l[1])) > tol * sx ||
        std::abs(glm::dot(l[0], l[2])) > tol * sx || std::abs(glm::dot(l[1], l[2])) > tol * sx)
      n.at("transform").fail("a sphere allows only translation, rotation and uniform scale");
    s.center = glm::dvec3(transform * glm::dvec4(center, 1.0));
    s.radius = radius * sx;
    s.frame = glm::mat3(l / sx);
    if (!within_float_range(s.center) || !(s.radius <= std::numeric_limits<float>::max()))
      (n.has("transform") ? n.at("transform") : n).fail("the transform takes the sphere to infinity");
    // Its area 4 pi r^2 (the light's power and pdf) and squared distances across it are floats on the
    // device: refused rather than turned into infinities and NaNs there.
    if (s.radius > kMaxSceneExtent) {
      char what[160];
      std::snprintf(what, sizeof what, "a sphere radius of %g is beyond the largest of %g (4 pi r^2 would overflow float)",
                    s.radius, kMaxSceneExtent);
      (radius > kMaxSceneExtent || !n.has("transform") ? n.at("radius") : n.at("transform")).fail(what);
    }
    return s;
  }

  ObjFile obj;
  PolygonSoup& soup = obj.soup;
  if (type == "mesh") {
    std::filesystem::path file = dir / n.at("file").string();
    s.label += " (" + n.at("file").string() + ")";
    const bool serialized = is_serialized_file(file.string());
    if (n.has("shape_index") && !serialized)
      n.at("shape_index").fail("shape_index goes with a Mitsuba .serialized file (which holds several shapes)");
    if (serialized) {
      if (from_mtl) n.at("material").fail("\"from_mtl\" needs an OBJ file with mtllib (a .serialized file has none)");
      soup = load_serialized(file.string(), n.has("shape_index") ? n.at("shape_index").count(0, 0xffffffffu) : 0,
                             scene.warnings);
    } else if (is_ply_stl_off_file(file.string())) {
      if (from_mtl) n.at("material").fail("\"from_mtl\" needs an OBJ file with mtllib (PLY, STL and OFF have no MTL files)");
      soup = load_ply_stl_off(file.string(), scene.warnings);
    } else {
      obj = load_obj_file(file.string(), from_mtl, scene.warnings);
    }
  } else {
    Node uvs = n.has("uvs") ? n.at("uvs") : n, colors = n.has("colors") ? n.at("colors") : n;
    check_inline_triangles(n.at("positions"), n.at("indices"), n.has("uvs") ? &uvs : nullptr,
                           n.has("colors") ? &colors : nullptr, soup);
  }
  // "vertex_colors": false renders the shape in its material's colour alone, whatever colours its file has.
  if (n.has("vertex_colors") && !n.at("vertex_colors").boolean()) soup.colors.clear();
  bool emits_mtl = false;  // an MTL material with Ke on some face
  for (uint32_t id : soup.materials) emits_mtl = emits_mtl || obj.materials[id].emission != glm::vec3(0);
  if (n.has("instance") && n.at("instance").boolean() && emits_mtl)
    n.at("instance").fail("the mesh emits (MTL Ke), and an emitter is not instanced (lights are sampled in world coordinates)");
  const bool instance = placements > 1 && !n.has("emission") && !emits_mtl &&
                        (n.has("instance") ? n.at("instance").boolean()
                                           : placements * soup.polygons.size() >= kMinInstancedTriangles);
  if (instance) {
    s.transform = transform;  // cleaned in its own coordinates, to be instanced
    *own_coordinates = true;
  } else {
    place_soup(soup, transform, n);  // cleaned in the world (a triangulation may depend on coordinates)
  }
  CleanOptions options;
  if (n.has("orient")) options.orient = n.at("orient").boolean();
  if (n.has("smooth")) options.smooth_normals = n.at("smooth").boolean();
  if (n.has("smooth_angle_degrees")) {
    Node angle = n.at("smooth_angle_degrees");
    if (!options.smooth_normals) angle.fail("has no effect without \"smooth\": true");
    double degrees = angle.number();
    if (!(degrees >= 0 && degrees <= 180)) angle.fail("expected an angle in [0, 180] degrees" + angle.got());
    options.smooth_angle_degrees = float(degrees);
  }
  try {
    s.mesh = clean_mesh(soup, options, s.clean);
  } catch (const SceneError& e) {
    n.fail(e.what());
  }
  if (n.has("subdivide")) {
    Node sub = n.at("subdivide");
    const double parts = sub.number();
    if (!(parts >= 1 && parts <= kMaxSubdivide && parts == std::floor(parts)))
      sub.fail("expected a whole number of parts per edge, 1 to " + std::to_string(kMaxSubdivide) + sub.got());
    subdivide_mesh(s.mesh, uint32_t(parts));
  }
  if (from_mtl) {
    std::vector<uint32_t> scene_material;
    std::vector<glm::vec3> emission;
    add_mtl_materials(obj, s.mesh.materials, scene, scene_material, emission);
    for (uint32_t id : s.mesh.materials) {
      s.triangle_materials.push_back(scene_material[id]);
      s.triangle_emission.push_back(emission[id]);
    }
  }
  // A texture needs texture coordinates: refuse rather than stretch one texel over a face.
  for (size_t t = 0; t < s.mesh.triangles.size(); ++t) {
    const MaterialDesc& m = scene.materials[triangle_material(s, t)];
    uint32_t polygon = s.mesh.source_polygon[t];
    if (m.color_texture == PC_INVALID || (!soup.uvs.empty() && !soup.uvs[polygon].empty())) continue;
    if (type == "mesh" && polygon >= obj.face_lines.size())
      n.fail((dir / n.at("file").string()).string() + ": face " + std::to_string(polygon) +
             " has no texture coordinates, but its material \"" + m.name + "\" has a texture");
    if (type == "mesh")
      n.fail((dir / n.at("file").string()).string() + ":" + std::to_string(obj.face_lines[polygon]) +
             ": face without texture coordinates (vt), but its material \"" + m.name + "\" has a texture");
    n.fail("material \"" + m.name + "\" has a texture, but the shape has no \"uvs\"");
  }
  return s;
}

// A point or spot light within kMaxSceneExtent of the camera: farther, squared distances to it would
// overflow float on the device.
void check_light_reach(const SceneDescription& scene, const LightDesc& light, const Node& where) {
  glm::dvec3 d = glm::abs(light.position - scene.camera.position);
  bool positioned = light.type == PC_LIGHT_POINT || light.type == PC_LIGHT_SPOT;
  if (positioned && !(std::max({d.x, d.y, d.z}) <= kMaxSceneExtent)) {
    char what[160];
    std::snprintf(what, sizeof what, "the light is %g from the camera, beyond the largest distance of %g",
                  std::max({d.x, d.y, d.z}), kMaxSceneExtent);
    where.fail(what);
  }
}

// "type": "gltf": the default scene of a glTF file placed by the shape's transform, one ShapeDesc per
// primitive that a node places (nodes sharing a mesh give copies), its materials and textures added to
// the scene's, its KHR_lights_punctual lights to the scene's lights.
void read_gltf_shape(const Node& n, const std::filesystem::path& dir, SceneDescription& scene) {
  n.expect_object({"type", "file", "transform", "instance", "vertex_colors"}, {"file"});
  const std::string file = (dir / n.at("file").string()).string();
  GltfScene gltf;
  try {
    gltf = load_gltf(file, scene.warnings);
  } catch (const SceneError& e) {
    n.at("file").fail(e.what());
  }
  const glm::dmat4 transform = n.has("transform") ? read_transform(n.at("transform")) : glm::dmat4(1.0);
  if (n.has("vertex_colors") && !n.at("vertex_colors").boolean())
    for (GltfPrimitive& p : gltf.primitives) p.soup.colors.clear();
  // A file that places no triangle (tinygltf reads some malformed files as empty) renders nothing of it.
  size_t placed_polygons = 0;
  for (const GltfPrimitive& p : gltf.primitives)
    placed_polygons += gltf.primitives[p.same_as == PC_INVALID ? &p - gltf.primitives.data() : p.same_as].soup.polygons.size();
  if (placed_polygons == 0)
    scene.warnings.push_back(file + ": the glTF scene places no triangles (" + std::to_string(gltf.primitives.size()) +
                             " primitives placed, " + std::to_string(gltf.lights.size()) + " lights)");
  // Materials are added when a primitive uses them, so that unused ones load no textures.
  std::vector<uint32_t> scene_material(gltf.materials.size(), PC_INVALID);
  std::vector<std::optional<TextureImage>> emission_images(gltf.images.size());
  auto image_loader = [&](uint32_t i) {
    const GltfImage& image = gltf.images[i];
    return [&image] { return image.file.empty() ? decode_texture_image(image.name, image.bytes) : load_texture_image(image.file); };
  };
  // Per primitive whose geometry the file holds (same_as unset): how many nodes place it, and its
  // instanced mesh where it has one (as for mesh shapes: asked for with "instance", or by default with
  // at least kMinInstancedTriangles polygons in all its copies, never for an emitter).
  std::vector<uint32_t> placements(gltf.primitives.size(), 0), instance_of(gltf.primitives.size(), PC_INVALID);
  for (size_t i = 0; i < gltf.primitives.size(); ++i)
    placements[gltf.primitives[i].same_as == PC_INVALID ? i : gltf.primitives[i].same_as]++;
  for (GltfPrimitive& p : gltf.primitives) {
    const GltfMaterial& gm = gltf.materials[p.material];
    if (scene_material[p.material] == PC_INVALID) {
      MaterialDesc m = gm.material;
      if (gm.color_image != PC_INVALID)
        m.color_texture = add_texture_image(scene, gltf.images[gm.color_image].name, image_loader(gm.color_image),
                                            gm.where + ".baseColorTexture", gm.color_wrap, true);
      if (gm.opacity_image != PC_INVALID) {
        std::string key = gltf.images[gm.opacity_image].name + " (alpha" +
                          (gm.alpha_cutoff >= 0 ? " at or above " + std::to_string(gm.alpha_cutoff) : "") + ")";
        auto load = [&] {
          TextureImage t = alpha_as_opacity(image_loader(gm.opacity_image)(), gm.alpha_factor, gm.alpha_cutoff);
          t.file = key;
          return t;
        };
        m.opacity_texture = add_texture_image(scene, key, load, gm.where + ".baseColorTexture", gm.color_wrap, true);
      }
      scene_material[p.material] = uint32_t(scene.materials.size());
      scene.materials.push_back(m);
    }
    ShapeDesc s;
    s.label = n.path + " (" + n.at("file").string() + ": " + p.where.substr(file.size() + 2) + ")";
    s.material = scene_material[p.material];
    s.emission = gm.emission;
    s.two_sided = gm.two_sided;
    s.transform = transform * p.transform;
    const uint32_t source = p.same_as == PC_INVALID ? uint32_t(&p - gltf.primitives.data()) : p.same_as;
    const GltfPrimitive& g = gltf.primitives[source];
    if ((gm.color_image != PC_INVALID || gm.emission_image != PC_INVALID) && g.soup.uvs.empty())
      n.fail(g.where + ": no TEXCOORD_0, but its material (" + gm.where + ") has a texture");
    const bool emits = gm.emission != glm::vec3(0);
    const bool instance = placements[source] > 1 && !emits &&
                          (n.has("instance") ? n.at("instance").boolean()
                                             : placements[source] * g.soup.polygons.size() >= kMinInstancedTriangles);
    if (instance) {
      // Nodes sharing a mesh: one instanced mesh, cleaned in its own coordinates, placed by each.
      if (instance_of[source] == PC_INVALID) {
        InstancedMesh m{s.label, {}, {}, {}};
        try {
          m.mesh = clean_mesh(g.soup, CleanOptions{}, m.clean);
        } catch (const SceneError& e) {
          n.fail(g.where + ": " + e.what());
        }
        set_bounds(m);
        instance_of[source] = uint32_t(scene.instanced_meshes.size());
        scene.instanced_meshes.push_back(std::move(m));
      }
      s.instance_of = instance_of[source];
      check_placement(scene.instanced_meshes[s.instance_of], s.transform, n);
      scene.shapes.push_back(std::move(s));
      continue;
    }
    // A copy, placed and then cleaned in the world, as a mesh shape placed once.
    PolygonSoup soup = placements[source] == 1 ? std::move(gltf.primitives[source].soup) : g.soup;
    place_soup(soup, s.transform, n);
    s.transform = glm::dmat4(1.0);
    try {
      s.mesh = clean_mesh(soup, CleanOptions{}, s.clean);
    } catch (const SceneError& e) {
      n.fail(g.where + ": " + e.what());
    }
    if (gm.emission_image != PC_INVALID) {
      // Emission is constant per triangle on the device: each triangle takes the emissive texel at
      // its uv centroid.
      std::optional<TextureImage>& image = emission_images[gm.emission_image];
      if (!image) {
        try {
          image = image_loader(gm.emission_image)();
        } catch (const SceneError& e) {
          throw SceneError(gm.where + ".emissiveTexture: " + e.what());
        }
        image->wrap = gm.emission_wrap;
        scene.warnings.push_back(gm.where + ": emissiveTexture taken per triangle at its uv centroid (emission is constant per triangle)");
      }
      for (const auto& uv : s.mesh.uvs)
        s.triangle_emission.push_back(gm.emission * texel_nearest(*image, (uv[0] + uv[1] + uv[2]) / 3.0f));
    }
    scene.shapes.push_back(std::move(s));
  }
  const glm::dmat3 linear(transform);
  for (LightDesc l : gltf.lights) {
    l.position = glm::dvec3(transform * glm::dvec4(l.position, 1.0));
    glm::dvec3 d = linear * glm::dvec3(l.direction);
    if (!(glm::length(d) > 0) || !within_float_range(l.position))
      (n.has("transform") ? n.at("transform") : n).fail(l.label + ": the transform leaves the light no position or direction");
    l.direction = glm::vec3(glm::normalize(d));
    check_light_reach(scene, l, n);
    scene.lights.push_back(l);
  }
}

// Whether anything emits: an emitting sphere, an emitting triangle left after clean-up (emission or an
// MTL material's Ke), or a point, spot, directional or environment light whose emission (and map) is not
// all zero. What the device scene then drops as well (zero-area emitters, a directional light in a scene
// of no size) is counted by `pathcl info`.
bool has_light(const SceneDescription& scene) {
  for (const ShapeDesc& s : scene.shapes)
    if (shape_emits(s) && (s.is_sphere || !s.mesh.triangles.empty())) return true;
  for (const LightDesc& l : scene.lights) {
    glm::vec3 e = l.emission;
    if (l.texture != PC_INVALID) e *= texture_max(scene.textures[l.texture]);
    if (e != glm::vec3(0)) return true;
  }
  return false;
}

// ---- The JSON text ----------------------------------------------------------------------------------
// nlohmann keeps the last of two equal keys in an object, and neither the DOM nor its SAX interface say
// where a value is. So one pass over the text finds what needs a line: keys given twice in one object,
// numbers beyond double range (which nlohmann reports without a position) and nesting deeper than any
// scene needs. It runs on text nlohmann has parsed, or parsed up to the bad number, so it need not check
// the syntax, only never read past the end.

// Far deeper than any scene needs (shapes[0].transform.matrix[0][0] is 5 levels); it bounds what the
// scan keeps per level.
constexpr size_t kMaxJsonDepth = 64;

struct TextFrame {
  bool object = false;
  bool expect_key = true;                         // objects: the next string is a key
  size_t index = 0;                               // arrays: the current element
  std::string key;                                // objects: the current key
  std::map<std::string, size_t> key_lines;        // objects: each key and its line
};

// The JSON path of the current value, as Node writes it: "shapes[0].radius".
std::string text_path(const std::vector<TextFrame>& frames) {
  std::string path;
  for (const TextFrame& f : frames)
    path += f.object ? (path.empty() ? "" : ".") + f.key : "[" + std::to_string(f.index) + "]";
  return path.empty() ? "(top level)" : path;
}

void check_json_text(const std::string& file, const std::string& text) {
  std::vector<TextFrame> frames;
  size_t line = 1;
  auto fail = [&](const std::string& what) {
    throw SceneError(file + ":" + std::to_string(line) + ": " + text_path(frames) + ": " + what);
  };
  for (size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (c == '\n') {
      ++line;
    } else if (c == '{' || c == '[') {
      if (frames.size() == kMaxJsonDepth) fail("nested deeper than " + std::to_string(kMaxJsonDepth) + " levels");
      frames.emplace_back().object = c == '{';
    } else if ((c == '}' || c == ']') && !frames.empty()) {
      frames.pop_back();
    } else if (c == ',' && !frames.empty()) {
      frames.back().expect_key = true;
      ++frames.back().index;
    } else if (c == '"') {
      size_t end = i + 1;  // the closing quote; no raw newline can come before it in JSON
      while (end < text.size() && text[end] != '"') end += text[end] == '\\' ? 2 : 1;
      if (end >= text.size()) return;
      if (!frames.empty() && frames.back().object && frames.back().expect_key) {
        TextFrame& f = frames.back();
        f.expect_key = false;
        try {
          f.key = json::parse(text.substr(i, end - i + 1)).get<std::string>();  // escapes decoded as nlohmann does
        } catch (const json::exception&) {
          return;  // not valid JSON: nlohmann says where
        }
        auto [first, added] = f.key_lines.emplace(f.key, line);
        if (!added)
          fail("duplicate key \"" + f.key + "\" (first at line " + std::to_string(first->second) + ")");
      }
      i = end;
    } else if (c == '-' || (c >= '0' && c <= '9')) {
      size_t end = std::min(text.find_first_not_of("+-.0123456789eE", i), text.size());
      std::string number = text.substr(i, end - i);
      if (!std::isfinite(std::strtod(number.c_str(), nullptr)))
        fail("malformed JSON: the number " + number + " is beyond the range of a double");
      i = end - 1;
    }
  }
}

}  // namespace

namespace {
const char* const kSamplerNames[] = {"independent", "stratified", "sobol", "halton"};  // by PC_SAMPLER_*
}

bool sampler_from_name(const std::string& name, uint32_t* sampler) {
  for (uint32_t i = 0; i < 4; ++i)
    if (name == kSamplerNames[i]) {
      *sampler = i;
      return true;
    }
  return false;
}

const char* sampler_name(uint32_t sampler) { return sampler < 4 ? kSamplerNames[sampler] : "unknown"; }

namespace {

// Whether the bytes are UTF-8 (as JSON text must be; an imported file's strings are not checked by a
// JSON parser): no stray continuation byte, truncated or overlong sequence, surrogate or code point
// beyond U+10FFFF.
bool is_utf8(const std::string& s) {
  for (size_t i = 0; i < s.size();) {
    const unsigned char c = static_cast<unsigned char>(s[i]);
    const size_t n = c < 0x80 ? 1 : (c >> 5) == 0x6 ? 2 : (c >> 4) == 0xe ? 3 : (c >> 3) == 0x1e ? 4 : 0;
    if (n == 0 || i + n > s.size()) return false;
    uint32_t code = n == 1 ? c : c & (0x7f >> n);
    for (size_t k = 1; k < n; ++k) {
      const unsigned char d = static_cast<unsigned char>(s[i + k]);
      if ((d >> 6) != 0x2) return false;
      code = (code << 6) | (d & 0x3f);
    }
    const uint32_t smallest[] = {0, 0, 0x80, 0x800, 0x10000};
    if (code < smallest[n] || code > 0x10ffff || (code >= 0xd800 && code <= 0xdfff)) return false;
    i += n;
  }
  return true;
}

// Every string of an imported document is UTF-8 (a mesh file name, a material name), or the file is
// refused at the entry that holds the string (nlohmann's dump would throw on it later).
void check_strings_are_utf8(const Node& n) {
  if (n.value.is_string() && !is_utf8(n.value.get_ref<const std::string&>()))
    n.fail("a string that is not valid UTF-8");
  if (n.value.is_object())
    for (auto& [key, _] : n.value.items()) {
      if (!is_utf8(key)) n.fail("a name that is not valid UTF-8");
      check_strings_are_utf8(n.at(key));
    }
  if (n.value.is_array())
    for (size_t i = 0; i < n.value.size(); ++i) check_strings_are_utf8(n.at(i));
}

// The JSON document of a scene file: parsed and scanned (a JSON file), or translated (ImportedScene).
ImportedScene scene_document(const std::string& path, const SceneDefines& defines) {
  const std::string text = read_input_file(path, kSceneInput);
  if (text.find_first_not_of(" \t\r\n") == std::string::npos)
    throw SceneError(path + ": the file is empty, expected a JSON scene (or a Mitsuba XML or pbrt scene)");
  if (text.rfind("\xff\xfe", 0) == 0 || text.rfind("\xfe\xff", 0) == 0)
    throw SceneError(path + ": the file is UTF-16, expected UTF-8 JSON");
  const SceneFileFormat format = scene_file_format(text);
  if (!defines.empty() && format != SceneFileFormat::mitsuba_xml)
    throw SceneError(path + ": -D " + defines[0].first + "=" + defines[0].second + " sets a Mitsuba <default>, and this is " +
                     (format == SceneFileFormat::pbrt ? "a pbrt" : "a JSON") + " scene");
  switch (format) {
    case SceneFileFormat::mitsuba_xml: {
      ImportedScene imported = import_mitsuba_xml(path, text, defines);
      imported.format = SceneFileFormat::mitsuba_xml;
      check_strings_are_utf8(Node{path, imported.scene, "", &imported.origins});
      return imported;
    }
    case SceneFileFormat::pbrt: {
      ImportedScene imported = import_pbrt(path, text);
      imported.format = SceneFileFormat::pbrt;
      check_strings_are_utf8(Node{path, imported.scene, "", &imported.origins});
      return imported;
    }
    case SceneFileFormat::json: break;
  }
  json root;
  try {
    root = json::parse(text);  // skips a UTF-8 byte order mark
  } catch (const json::parse_error& e) {
    throw SceneError(malformed_json_message(path, e.what()));
  } catch (const json::exception&) {
    // A number beyond double range (out_of_range), reported without a position: the scan finds it.
    check_json_text(path, text);
    throw SceneError(path + ": malformed JSON: a number is beyond the range of a double");
  }
  check_json_text(path, text);
  return ImportedScene{std::move(root), {}, {}, SceneFileFormat::json};
}

}  // namespace

ImportedScene load_scene_document(const std::string& path, const SceneDefines& defines) {
  return scene_document(path, defines);
}

SceneDescription load_scene(const std::string& path, const SceneDefines& defines) {
  return load_scene(path, scene_document(path, defines));
}

SceneDescription load_scene(const std::string& path, const ImportedScene& document) {
  const json& root = document.scene;
  SceneDescription scene;
  scene.path = path;
  scene.warnings = document.warnings;
  Node top{path, root, "", &document.origins};
  if (!root.is_object())
    top.fail(std::string("expected an object with camera, materials and shapes, got ") + (root.is_array() ? "an " : "a ") +
             root.type_name());
  top.expect_object({"camera", "materials", "shapes", "lights", "render"}, {"camera", "materials", "shapes"});
  std::filesystem::path dir = std::filesystem::path(path).parent_path();
  scene.camera = top.at("camera").value.is_object() && top.at("camera").has("from_gltf")
                     ? read_gltf_camera(top.at("camera"), dir, scene.warnings)
                     : read_camera(top.at("camera"));

  Node mats = top.at("materials");
  if (!mats.value.is_object()) mats.fail("expected an object of named materials");
  std::map<std::string, uint32_t> by_name;
  for (auto& [name, _] : mats.value.items()) {
    if (name == "from_mtl") mats.at(name).fail("the name \"from_mtl\" is reserved (a mesh's materials from its MTL files)");
    by_name[name] = uint32_t(scene.materials.size());
    scene.materials.push_back(read_material(mats.at(name), name, scene, dir));
  }
  // A mesh that several shapes place with the same settings (everything but the transform) becomes
  // one instanced mesh, loaded once, when they ask for it ("instance": true) or, by default, when its
  // copies would hold at least kMinInstancedTriangles polygons; never when it emits (lights are sampled
  // in world coordinates). Otherwise each placement is a copy, loaded and cleaned in the world.
  std::map<std::string, uint32_t> placements;
  for (const Node& s : top.at("shapes").array()) {
    std::string key = instance_key(s);
    if (!key.empty()) placements[key]++;
  }
  std::map<std::string, ShapeDesc> first_instance;  // per key: the first placement, without its mesh
  for (const Node& s : top.at("shapes").array()) {
    if (s.value.is_object() && s.has("type") && s.at("type").value == "gltf") {
      read_gltf_shape(s, dir, scene);
      continue;
    }
    std::string key = instance_key(s);
    auto found = first_instance.find(key);
    if (found != first_instance.end()) {
      // A further placement: the settings are the first's (the same JSON), the label and transform its own.
      ShapeDesc shape = found->second;
      shape.label = s.path + (s.has("file") ? " (" + s.at("file").string() + ")" : "");
      shape.transform = s.has("transform") ? read_transform(s.at("transform")) : glm::dmat4(1.0);
      check_placement(scene.instanced_meshes[shape.instance_of], shape.transform, s);
      scene.shapes.push_back(std::move(shape));
      continue;
    }
    bool own_coordinates = false;
    ShapeDesc shape = read_shape(s, dir, by_name, scene, key.empty() ? 1 : placements[key], &own_coordinates);
    if (own_coordinates) {
      shape.instance_of = uint32_t(scene.instanced_meshes.size());
      scene.instanced_meshes.push_back({shape.label, std::move(shape.mesh), shape.clean, std::move(shape.triangle_materials)});
      set_bounds(scene.instanced_meshes.back());
      check_placement(scene.instanced_meshes.back(), shape.transform, s);
      shape.mesh = TriangleMesh{};
      shape.clean = CleanReport{};
      shape.triangle_materials.clear();
      shape.triangle_emission.clear();  // all zero: an instanced mesh does not emit
      first_instance.emplace(key, shape);
    }
    scene.shapes.push_back(std::move(shape));
  }
  if (top.has("lights")) {
    bool environment = false;
    for (const Node& l : top.at("lights").array()) {
      LightDesc light = read_light(l);
      check_light_reach(scene, light, l.has("position") ? l.at("position") : l);
      if (light.type == PC_LIGHT_ENVIRONMENT) {
        if (environment) l.fail("a scene has at most one environment light");
        environment = true;
        if (l.has("file") && l.at("file").value.is_object() && l.at("file").has("checkerboard"))
          l.at("file").fail("a checkerboard cannot be an environment map (an environment takes a lat-long image file)");
        if (l.has("file")) light.texture = add_texture(scene, l.at("file"), dir, PC_WRAP_REPEAT, false);
        if (light.texture != PC_INVALID && light.mapping != PC_ENV_LAT_LONG) {
          const TextureImage& map = scene.textures[light.texture];
          if (map.width != map.height)
            l.at("file").fail(map.file + " is " + std::to_string(map.width) + " x " + std::to_string(map.height) +
                              " texels: an equal_area map is a square image (pbrt-v4's equal-area octahedral map)");
        }
      }
      scene.lights.push_back(light);
    }
  }

  if (top.has("render")) {
    Node r = top.at("render");
    r.expect_object({"spp", "max_depth", "seed", "sampler", "integrator", "aovs"});
    if (r.has("spp")) scene.render.spp = r.at("spp").count(1, kMaxSpp);
    if (r.has("max_depth")) scene.render.max_depth = r.at("max_depth").count(0, kMaxDepth);
    if (r.has("seed")) scene.render.seed = r.at("seed").count(0, 0xffffffffu);
    if (r.has("sampler") && !sampler_from_name(r.at("sampler").string(), &scene.render.sampler))
      r.at("sampler").fail("unknown sampler \"" + r.at("sampler").string() +
                           "\" (expected independent, stratified, sobol or halton)");
    if (r.has("integrator")) {
      Node in = r.at("integrator");
      scene.render.integrator_place = in.place();
      if (in.value.is_object()) {  // {"type": NAME, and the technique's own options}
        if (!in.has("type")) in.fail("missing key \"type\" (the integrator's name)");
        scene.render.integrator = in.at("type").string();
        json options = in.value;
        options.erase("type");
        scene.render.integrator_options = options.dump();
      } else {
        if (!in.value.is_string()) in.fail("expected an integrator's name or {\"type\": NAME, ...options}");
        scene.render.integrator = in.string();
      }
    }
    if (r.has("aovs")) {
      for (const Node& a : r.at("aovs").array()) {
        scene.render.aovs.push_back(a.string());
        scene.render.aov_places.push_back(a.place());
      }
    }
  }
  if (!has_light(scene))
    scene.warnings.push_back(path + ": the scene has no light (no shape or MTL material emits, and no entry of "
                             "\"lights\" emits): it renders black");
  return scene;
}
