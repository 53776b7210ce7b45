// Reads the JSON scene file (docs/scene-format.md), checking every key and type, and loads, transforms
// and cleans the meshes it names.
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <limits>
#include <map>
#include <sstream>

#include <glm/geometric.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/mat3x3.hpp>
#include <glm/mat4x4.hpp>
#include <nlohmann/json.hpp>

#include "scene/scene_description.h"
#include "scene/scene_error.h"

using nlohmann::json;

namespace {

// A JSON value with its path in the file, so every error can say where it is.
struct Node {
  const std::string& file;
  const json& value;
  std::string path;

  [[noreturn]] void fail(const std::string& what) const {
    throw SceneError(file + ": " + (path.empty() ? "(top level)" : path) + ": " + what);
  }
  Node at(const std::string& key) const {
    return {file, value.at(key), path.empty() ? key : path + "." + key};
  }
  Node at(size_t i) const { return {file, value.at(i), path + "[" + std::to_string(i) + "]"}; }
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
  double number() const {
    if (!value.is_number()) fail("expected a number");
    double d = value.get<double>();
    // Colours and settings end up as floats, coordinates as floats relative to the camera: 1e39 would
    // become infinity there.
    if (!std::isfinite(d) || std::abs(d) > double(std::numeric_limits<float>::max()))
      fail("expected a finite number within float range");
    return d;
  }
  double positive() const {
    double d = number();
    if (!(d > 0)) fail("expected a number > 0");
    return d;
  }
  uint32_t count(uint32_t lo, uint32_t hi) const {
    if (!value.is_number_integer()) fail("expected an integer");
    if (value.is_number_unsigned() ? value.get<uint64_t>() > hi : value.get<int64_t>() < int64_t(lo) ||
                                                                       value.get<int64_t>() > int64_t(hi))
      fail("expected an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
    return uint32_t(value.get<int64_t>());
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

CameraDesc read_camera(const Node& n) {
  n.expect_object({"type", "position", "look_at", "up", "fov_y_degrees", "width", "height"},
                  {"position", "look_at", "width", "height"});
  if (n.has("type") && n.at("type").string() != "perspective")
    n.at("type").fail("unknown camera type \"" + n.at("type").string() + "\" (expected \"perspective\")");
  CameraDesc c;
  c.position = n.at("position").dvec3();
  c.look_at = n.at("look_at").dvec3();
  if (n.has("up")) c.up = n.at("up").dvec3();
  if (n.has("fov_y_degrees")) {
    c.fov_y_degrees = n.at("fov_y_degrees").positive();
    if (c.fov_y_degrees >= 180) n.at("fov_y_degrees").fail("expected a field of view below 180 degrees");
  }
  c.width = n.at("width").count(1, 16384);
  c.height = n.at("height").count(1, 16384);
  glm::dvec3 forward = c.look_at - c.position;
  if (glm::length(forward) == 0) n.fail("position and look_at coincide");
  if (glm::length(glm::cross(forward, c.up)) == 0)
    (n.has("up") ? n.at("up") : n).fail("up is parallel to the view direction (set camera.up)");
  return c;
}

MaterialDesc read_material(const Node& n, const std::string& name) {
  n.expect_object({"type", "reflectance"}, {"type"});
  MaterialDesc m;
  m.name = name;
  m.type = n.at("type").string();
  if (m.type != "diffuse") n.at("type").fail("unknown material type \"" + m.type + "\" (expected \"diffuse\")");
  if (n.has("reflectance")) {
    m.reflectance = n.at("reflectance").color();
    if (m.reflectance.x > 1 || m.reflectance.y > 1 || m.reflectance.z > 1)
      n.at("reflectance").fail("expected values in [0, 1]");
  }
  return m;
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

// Validates the soup's indices and coordinates (OBJ files are checked line by line in load_obj).
void check_inline_triangles(const Node& positions, const Node& indices, PolygonSoup& soup) {
  for (const Node& p : positions.array()) soup.positions.push_back(p.dvec3());
  for (const Node& f : indices.array()) {
    if (!f.value.is_array() || f.value.size() != 3) f.fail("expected 3 vertex indices");
    std::vector<uint32_t> poly;
    for (int k = 0; k < 3; ++k) {
      Node i = f.at(k);
      if (!i.value.is_number_integer()) i.fail("expected an integer vertex index");
      int64_t idx = i.value.get<int64_t>();
      if (idx < 0 || idx >= int64_t(soup.positions.size()))
        i.fail("vertex index " + std::to_string(idx) + " out of range (" +
               std::to_string(soup.positions.size()) + " positions)");
      poly.push_back(uint32_t(idx));
    }
    soup.polygons.push_back(poly);
  }
}

ShapeDesc read_shape(const Node& n, const std::filesystem::path& dir,
                     const std::map<std::string, uint32_t>& materials) {
  if (!n.value.is_object() || !n.has("type")) n.fail("expected an object with a \"type\"");
  std::string type = n.at("type").string();
  ShapeDesc s;
  if (type == "mesh")
    n.expect_object({"type", "file", "material", "emission", "two_sided", "transform", "orient", "smooth"},
                    {"file", "material"});
  else if (type == "triangles")
    n.expect_object({"type", "positions", "indices", "material", "emission", "two_sided", "transform",
                     "orient", "smooth"},
                    {"positions", "indices", "material"});
  else if (type == "sphere")
    n.expect_object({"type", "center", "radius", "material", "emission", "two_sided", "transform",
                     "flip_normals"},
                    {"radius", "material"});
  else
    n.at("type").fail("unknown shape type \"" + type + "\" (expected mesh, triangles or sphere)");

  std::string material = n.at("material").string();
  auto it = materials.find(material);
  if (it == materials.end()) n.at("material").fail("unknown material \"" + material + "\"");
  s.material = it->second;
  if (n.has("emission")) s.emission = n.at("emission").color();
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

  PolygonSoup soup;
  if (type == "mesh") {
    std::filesystem::path file = dir / n.at("file").string();
    s.label += " (" + n.at("file").string() + ")";
    soup = load_obj(file.string());
  } else {
    check_inline_triangles(n.at("positions"), n.at("indices"), soup);
  }
  for (glm::dvec3& p : soup.positions) {
    p = glm::dvec3(transform * glm::dvec4(p, 1.0));
    if (!within_float_range(p))
      (n.has("transform") ? n.at("transform") : n).fail("the transform takes a vertex to infinity");
  }
  // A mirroring transform turns counter-clockwise into clockwise: swap winding so the front stays the front.
  if (glm::determinant(glm::dmat3(transform)) < 0)
    for (auto& poly : soup.polygons) std::reverse(poly.begin(), poly.end());
  CleanOptions options;
  if (n.has("orient")) options.orient = n.at("orient").boolean();
  if (n.has("smooth")) options.smooth_normals = n.at("smooth").boolean();
  try {
    s.mesh = clean_mesh(soup, options, s.clean);
  } catch (const SceneError& e) {
    n.fail(e.what());
  }
  return s;
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

SceneDescription load_scene(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw SceneError(path + ": cannot open the scene file");
  json root;
  try {
    root = json::parse(in);
  } catch (const json::exception& e) {
    // nlohmann's message names the line and column. Not only parse_error: a number too large for a
    // double (1e400) is an out_of_range error.
    throw SceneError(path + ": malformed JSON: " + e.what());
  }
  SceneDescription scene;
  scene.path = path;
  Node top{path, root, ""};
  top.expect_object({"camera", "materials", "shapes", "render"}, {"camera", "materials", "shapes"});
  scene.camera = read_camera(top.at("camera"));

  Node mats = top.at("materials");
  if (!mats.value.is_object()) mats.fail("expected an object of named materials");
  std::map<std::string, uint32_t> by_name;
  for (auto& [name, _] : mats.value.items()) {
    by_name[name] = uint32_t(scene.materials.size());
    scene.materials.push_back(read_material(mats.at(name), name));
  }
  std::filesystem::path dir = std::filesystem::path(path).parent_path();
  for (const Node& s : top.at("shapes").array()) scene.shapes.push_back(read_shape(s, dir, by_name));

  if (top.has("render")) {
    Node r = top.at("render");
    r.expect_object({"spp", "max_depth", "seed", "sampler"});
    if (r.has("spp")) scene.render.spp = r.at("spp").count(1, 1u << 24);
    if (r.has("max_depth")) scene.render.max_depth = r.at("max_depth").count(0, 1024);
    if (r.has("seed")) scene.render.seed = r.at("seed").count(0, 0xffffffffu);
    if (r.has("sampler") && !sampler_from_name(r.at("sampler").string(), &scene.render.sampler))
      r.at("sampler").fail("unknown sampler \"" + r.at("sampler").string() +
                           "\" (expected independent, stratified, sobol or halton)");
  }
  return scene;
}
