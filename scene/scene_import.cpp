// What scene/scene_import.h shares between the importers and the loader: telling the formats apart and
// moving a document's file references to another directory.
#include "scene/scene_import.h"

#include "scene/scene_error.h"

#include <cctype>
#include <cmath>
#include <filesystem>

#include <glm/geometric.hpp>
#include <glm/vec4.hpp>

namespace {

// The words that can start a pbrt file (its directives; a file of only an Include also starts so).
bool is_pbrt_directive(const std::string& word) {
  static const char* const kDirectives[] = {
      "LookAt", "Camera", "Film", "Sampler", "Integrator", "PixelFilter", "ColorSpace", "Option", "WorldBegin",
      "AttributeBegin", "TransformBegin", "Identity", "Translate", "Scale", "Rotate", "Transform",
      "ConcatTransform", "CoordinateSystem", "CoordSysTransform", "ReverseOrientation", "Material",
      "MakeNamedMaterial", "NamedMaterial", "Texture", "LightSource", "AreaLightSource", "Shape", "ObjectBegin",
      "ObjectInstance", "Include", "Import", "Attribute", "MakeNamedMedium", "MediumInterface", "ActiveTransform",
      "TransformTimes", "Accelerator"};
  for (const char* d : kDirectives)
    if (word == d) return true;
  return false;
}

bool is_space(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n'; }

}  // namespace

SceneDefines parse_scene_defines(const std::vector<std::string>& words) {
  SceneDefines defines;
  for (const std::string& word : words) {
    const size_t equals = word.find('=');
    if (equals == std::string::npos || equals == 0)
      throw SceneError("-D " + word + ": expected NAME=VALUE (a Mitsuba scene's <default name=\"NAME\">)");
    defines.emplace_back(word.substr(0, equals), word.substr(equals + 1));
  }
  return defines;
}

SceneFileFormat scene_file_format(const std::string& text) {
  size_t i = text.rfind("\xef\xbb\xbf", 0) == 0 ? 3 : 0;
  for (;;) {
    while (i < text.size() && is_space(text[i])) ++i;
    if (i < text.size() && text[i] == '#') {  // a pbrt comment: pbrt if a directive follows
      i = text.find('\n', i);
      if (i == std::string::npos) return SceneFileFormat::json;
      continue;
    }
    break;
  }
  if (i < text.size() && text[i] == '<') return SceneFileFormat::mitsuba_xml;
  size_t end = i;
  while (end < text.size() && std::isalpha(static_cast<unsigned char>(text[end]))) ++end;
  return is_pbrt_directive(text.substr(i, end - i)) ? SceneFileFormat::pbrt : SceneFileFormat::json;
}

void rebase_scene_paths(nlohmann::json& scene, const std::string& from_dir, const std::string& to_dir) {
  namespace fs = std::filesystem;
  const fs::path from = fs::absolute(from_dir.empty() ? "." : from_dir);
  const fs::path to = fs::absolute(to_dir.empty() ? "." : to_dir);
  auto rebase = [&](nlohmann::json& value) {
    if (!value.is_string()) return;  // the loader names what is wrong with it
    fs::path p = value.get<std::string>();
    if (p.is_absolute()) return;
    value = (from / p).lexically_normal().lexically_relative(to).generic_string();
  };
  auto rebase_key = [&](nlohmann::json& object, const char* key) {
    if (object.is_object() && object.contains(key)) rebase(object[key]);
  };
  if (scene.contains("camera")) rebase_key(scene["camera"], "from_gltf");
  if (scene.contains("materials") && scene["materials"].is_object())
    for (auto& [name, material] : scene["materials"].items())
      if (material.is_object())
        for (auto& [key, value] : material.items()) rebase_key(value, "texture");
  for (const char* list : {"shapes", "lights"})
    if (scene.contains(list) && scene[list].is_array())
      for (auto& entry : scene[list]) rebase_key(entry, "file");
}

namespace {

bool all_numbers(const nlohmann::json& array) {
  for (const auto& v : array)
    if (!v.is_number()) return false;
  return true;
}

void write_json(const nlohmann::json& v, int indent, std::string& out) {
  const std::string pad(size_t(indent + 2), ' '), close(size_t(indent), ' ');
  if (v.is_object() && !v.empty()) {
    out += "{\n";
    size_t i = 0;
    for (auto& [key, value] : v.items()) {
      out += pad + nlohmann::json(key).dump() + ": ";
      write_json(value, indent + 2, out);
      out += ++i < v.size() ? ",\n" : "\n";
    }
    out += close + "}";
  } else if (v.is_array() && !v.empty() && !all_numbers(v)) {
    out += "[\n";
    for (size_t i = 0; i < v.size(); ++i) {
      out += pad;
      write_json(v[i], indent + 2, out);
      out += i + 1 < v.size() ? ",\n" : "\n";
    }
    out += close + "]";
  } else {
    out += v.dump();  // a number, string, empty container or an array of numbers, on one line
  }
}

}  // namespace

std::string scene_json_text(const nlohmann::json& scene) {
  std::string out;
  write_json(scene, 0, out);
  return out + "\n";
}

nlohmann::json vec_json(const glm::dvec3& v) { return nlohmann::json::array({v.x, v.y, v.z}); }

nlohmann::json matrix_json(const glm::dmat4& m) {
  nlohmann::json rows = nlohmann::json::array();
  for (int r = 0; r < 4; ++r) rows.push_back(nlohmann::json::array({m[0][r], m[1][r], m[2][r], m[3][r]}));
  return rows;
}

bool is_identity(const glm::dmat4& m, double tolerance) {
  for (int c = 0; c < 4; ++c)
    for (int r = 0; r < 4; ++r)
      if (!(std::abs(m[c][r] - (c == r ? 1.0 : 0.0)) <= tolerance)) return false;
  return true;
}

glm::dvec3 transform_point(const glm::dmat4& m, const glm::dvec3& p) { return glm::dvec3(m * glm::dvec4(p, 1.0)); }
glm::dvec3 transform_vector(const glm::dmat4& m, const glm::dvec3& v) { return glm::dvec3(m * glm::dvec4(v, 0.0)); }

nlohmann::json camera_frame_json(const glm::dvec3& position, const glm::dvec3& forward, const glm::dvec3& up,
                                 const glm::dvec3& image_right) {
  nlohmann::json camera = {{"position", vec_json(position)}, {"look_at", vec_json(position + forward)}, {"up", vec_json(up)}};
  if (glm::dot(glm::cross(forward, up), image_right) < 0) camera["handedness"] = "left";
  return camera;
}
