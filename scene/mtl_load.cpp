// MTL files read line by line (not through tinyobjloader, which reads "Kd 0.5" as (0.5, 0, 0) and knows
// no line numbers), then mapped onto our material types.
#include "scene/mtl_load.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <set>
#include <sstream>

#include "scene/input_file.h"
#include "scene/scene_error.h"
#include "scene/scene_limits.h"

namespace {

// The statements of one newmtl block, as given.
struct RawMaterial {
  std::string name, where;
  bool has_kd = false, has_ks = false, has_ke = false, has_tf = false, has_ns = false, has_ni = false;
  glm::vec3 kd{0}, ks{0}, ke{0}, tf{1};
  float ns = 0, ni = 1.5f, d = 1;
  int illum = -1;
  std::string map_kd, map_kd_where;
  uint32_t map_kd_wrap = PC_WRAP_REPEAT;
  std::vector<std::string> warnings;
  std::set<std::string> ignored;
};

std::string trim(const std::string& s) {
  size_t a = s.find_first_not_of(" \t\r"), b = s.find_last_not_of(" \t\r");
  return a == std::string::npos ? "" : s.substr(a, b - a + 1);
}

float parse_number(const std::string& word, const std::string& where, const std::string& key) {
  char* end = nullptr;
  double value = std::strtod(word.c_str(), &end);
  if (word.empty() || *end != '\0' || !std::isfinite(value) || std::abs(value) > std::numeric_limits<float>::max())
    throw SceneError(where + ": " + key + ": expected a finite number, got \"" + word + "\"");
  return float(value);
}

// "r [g b]": one number means grey (as the MTL specification says); values must be >= 0, and <= 1 when
// `albedo` (a reflectance or transmittance).
glm::vec3 parse_color(std::istringstream& words, const std::string& where, const std::string& key, bool albedo) {
  std::vector<std::string> parts;
  for (std::string w; words >> w;) parts.push_back(w);
  if (!parts.empty() && (parts[0] == "spectral" || parts[0] == "xyz"))
    throw SceneError(where + ": " + key + " " + parts[0] + " is not supported (expected r g b)");
  if (parts.size() != 1 && parts.size() != 3)
    throw SceneError(where + ": " + key + ": expected 1 or 3 numbers");
  glm::vec3 c;
  for (int k = 0; k < 3; ++k) c[k] = parse_number(parts[parts.size() == 1 ? 0 : k], where, key);
  if (c.x < 0 || c.y < 0 || c.z < 0) throw SceneError(where + ": " + key + ": expected non-negative values");
  if (albedo && (c.x > 1 || c.y > 1 || c.z > 1)) throw SceneError(where + ": " + key + ": expected values in [0, 1]");
  return c;
}

float parse_scalar(std::istringstream& words, const std::string& where, const std::string& key) {
  std::string word, extra;
  words >> word;
  if (words >> extra) throw SceneError(where + ": " + key + ": expected one number");
  return parse_number(word, where, key);
}

// map_Kd [-clamp on|off] [-blendu on|off] [-blendv on|off] FILE. Other options change how the image is
// placed or its values (-o, -s, -mm, ...): rather than ignore them and render something else, refuse.
void parse_map_kd(const std::string& rest, const std::string& where, const std::filesystem::path& dir,
                  RawMaterial& m) {
  size_t pos = 0;
  // The next whitespace-separated word from pos on ("" at the end), advancing pos past it.
  auto next_word = [&](size_t& start) {
    start = rest.find_first_not_of(" \t\r", pos);
    if (start == std::string::npos) return std::string();
    size_t end = rest.find_first_of(" \t\r", start);
    pos = end == std::string::npos ? rest.size() : end;
    return rest.substr(start, pos - start);
  };
  size_t start = 0;
  std::string word = next_word(start);
  while (word.size() > 1 && word[0] == '-') {
    if (word != "-clamp" && word != "-blendu" && word != "-blendv")
      throw SceneError(where + ": map_Kd option " + word + " is not supported (only -clamp, -blendu, -blendv)");
    size_t unused = 0;
    std::string value = next_word(unused);
    if (value != "on" && value != "off") throw SceneError(where + ": map_Kd " + word + ": expected on or off");
    if (word == "-clamp") m.map_kd_wrap = value == "on" ? PC_WRAP_CLAMP : PC_WRAP_REPEAT;
    word = next_word(start);
  }
  std::string file = word.empty() ? "" : trim(rest.substr(start));
  if (file.empty()) throw SceneError(where + ": map_Kd: expected a file name");
  m.map_kd = resolve_written_path(dir, file, where + ": map_Kd", m.warnings);
  m.map_kd_where = where;
}

std::vector<RawMaterial> read_raw(const std::string& path) {
  read_input_file(path, kMaterialInput, 512);
  std::ifstream in(path);
  if (!in) throw SceneError(path + ": cannot open the material file");
  std::filesystem::path dir = std::filesystem::path(path).parent_path();
  std::vector<RawMaterial> materials;
  std::set<std::string> names;
  std::string line;
  for (size_t number = 1; read_line(in, line); ++number) {
    std::string where = path + ":" + std::to_string(number);
    std::istringstream words(line);
    std::string key;
    if (!(words >> key) || key[0] == '#') continue;
    if (key == "newmtl") {
      std::string rest;
      std::getline(words, rest);
      RawMaterial m;
      m.name = trim(rest);
      m.where = where;
      if (m.name.empty()) throw SceneError(where + ": newmtl: expected a material name");
      if (!names.insert(m.name).second) throw SceneError(where + ": material \"" + m.name + "\" defined twice");
      materials.push_back(m);
      continue;
    }
    if (materials.empty()) throw SceneError(where + ": " + key + " before any newmtl");
    RawMaterial& m = materials.back();
    if (key == "Kd") {
      m.kd = parse_color(words, where, key, true);
      m.has_kd = true;
    } else if (key == "Ks") {
      m.ks = parse_color(words, where, key, true);
      m.has_ks = true;
    } else if (key == "Ke") {
      m.ke = parse_color(words, where, key, false);
      if (m.ke.x > kMaxLightValue || m.ke.y > kMaxLightValue || m.ke.z > kMaxLightValue)
        throw SceneError(where + ": Ke: expected values of at most 1e12");
      m.has_ke = true;
    } else if (key == "Tf" || key == "Kt") {
      m.tf = parse_color(words, where, key, true);
      m.has_tf = true;
    } else if (key == "Ns") {
      m.ns = parse_scalar(words, where, key);
      m.has_ns = true;
    } else if (key == "Ni") {
      m.ni = parse_scalar(words, where, key);
      if (!(m.ni > 0 && m.ni <= 10)) throw SceneError(where + ": Ni: expected an index of refraction in (0, 10]");
      m.has_ni = true;
    } else if (key == "d" || key == "Tr") {
      float v = parse_scalar(words, where, key);
      if (!(v >= 0 && v <= 1)) throw SceneError(where + ": " + key + ": expected a number in [0, 1]");
      m.d = key == "d" ? v : 1 - v;
    } else if (key == "illum") {
      std::string word;
      words >> word;
      char* end = nullptr;
      long v = std::strtol(word.c_str(), &end, 10);
      if (word.empty() || *end != '\0' || v < 0 || v > 10)
        throw SceneError(where + ": illum: expected an integer in [0, 10]");
      m.illum = int(v);
    } else if (key == "map_Kd") {
      std::string rest;
      std::getline(words, rest);
      parse_map_kd(rest, where, dir, m);
    } else {
      m.ignored.insert(key);
    }
  }
  return materials;
}

}  // namespace

std::vector<MtlMaterial> load_mtl(const std::string& path) {
  std::vector<MtlMaterial> result;
  for (const RawMaterial& raw : read_raw(path)) {
    MtlMaterial out;
    out.name = raw.name;
    out.file = path;
    out.where = raw.where;
    out.warnings = raw.warnings;
    out.ignored = raw.ignored;
    out.emission = raw.ke;
    MaterialDesc& m = out.material;
    m.name = raw.name;
    // Without Kd, a texture stands alone (Kd 1) and a plain material gets our default reflectance.
    glm::vec3 kd = raw.has_kd ? raw.kd : glm::vec3(raw.map_kd.empty() ? 0.5f : 1.0f);
    if (raw.illum == 7 || raw.d < 1) {
      m.type = "dielectric";
      m.type_id = PC_MAT_DIELECTRIC;
      m.ior = raw.has_ni ? raw.ni : 1.5f;
      m.color = raw.has_tf ? raw.tf : glm::vec3(1);
      if (!raw.map_kd.empty())
        out.warnings.push_back(raw.map_kd_where + ": map_Kd ignored: material \"" + raw.name +
                               "\" is a dielectric, which has no diffuse colour");
    } else if (raw.ks.x > 0 || raw.ks.y > 0 || raw.ks.z > 0) {
      m.type = "phong";
      m.type_id = PC_MAT_PHONG;
      m.color = kd;
      m.specular = raw.ks;
      m.exponent = std::clamp(raw.ns, 1.0f, 1e5f);
      out.texture = raw.map_kd;
    } else {
      m.type = "diffuse";
      m.type_id = PC_MAT_DIFFUSE;
      m.color = kd;
      out.texture = raw.map_kd;
    }
    if (!out.texture.empty()) {
      out.texture_where = raw.map_kd_where;
      out.texture_wrap = raw.map_kd_wrap;
    }
    result.push_back(out);
  }
  return result;
}

void limit_phong_energy(MaterialDesc& m, glm::vec3 diffuse_max, const std::string& where,
                        std::vector<std::string>& warnings) {
  glm::vec3 sum = diffuse_max + m.specular;
  float largest = std::max({sum.x, sum.y, sum.z});
  if (largest <= 1) return;
  m.color /= largest;
  m.specular /= largest;
  std::ostringstream text;
  text << where << ": material \"" << m.name << "\": Kd + Ks reaches " << largest
       << " (more than 1 would create energy): both scaled by " << 1 / largest;
  warnings.push_back(text.str());
}
