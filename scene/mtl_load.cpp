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
  bool has_d = false;
  std::string map_kd, map_kd_where;
  uint32_t map_kd_wrap = PC_WRAP_REPEAT;
  std::string map_d, map_d_where;
  uint32_t map_d_wrap = PC_WRAP_REPEAT;
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
// map_Kd or map_d (key): options, then a file name resolved against dir; sets file and wrap.
void parse_map(const std::string& rest, const std::string& where, const std::filesystem::path& dir,
               const std::string& key, std::string& file_out, uint32_t& wrap, std::vector<std::string>& warnings) {
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
      throw SceneError(where + ": " + key + " option " + word + " is not supported (only -clamp, -blendu, -blendv)");
    size_t unused = 0;
    std::string value = next_word(unused);
    if (value != "on" && value != "off") throw SceneError(where + ": " + key + " " + word + ": expected on or off");
    if (word == "-clamp") wrap = value == "on" ? PC_WRAP_CLAMP : PC_WRAP_REPEAT;
    word = next_word(start);
  }
  std::string file = word.empty() ? "" : trim(rest.substr(start));
  if (file.empty()) throw SceneError(where + ": " + key + ": expected a file name");
  file_out = resolve_written_path(dir, file, where + ": " + key, warnings);
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
      m.has_d = true;
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
      parse_map(rest, where, dir, key, m.map_kd, m.map_kd_wrap, m.warnings);
      m.map_kd_where = where;
    } else if (key == "map_d") {
      std::string rest;
      std::getline(words, rest);
      parse_map(rest, where, dir, key, m.map_d, m.map_d_wrap, m.warnings);
      m.map_d_where = where;
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
    // Glass only from a transparency illum model that refracts (4, 6, 7) with an Ni; d is then not an
    // opacity. Otherwise d (or 1 - Tr) is an opacity (a cut-out) only with a transparency model (4, 6, 7,
    // 9) or, with a warning, without illum; other illum models have no transparency, and exporters write
    // d 0 with them on opaque materials (Blender's Sponza: d 0 and illum 1 on 22 of 25 materials), so d is
    // ignored there, with a warning. map_d is always an opacity map.
    bool transparency_model = raw.illum == 4 || raw.illum == 6 || raw.illum == 7 || raw.illum == 9;
    bool glass = (raw.illum == 4 || raw.illum == 6 || raw.illum == 7) && raw.has_ni;
    if (glass) {
      m.type = "dielectric";
      m.type_id = PC_MAT_DIELECTRIC;
      m.ior = raw.ni;
      m.color = raw.has_tf ? raw.tf : glm::vec3(1);
      out.warnings.push_back(raw.where + ": material \"" + raw.name + "\" rendered as glass of ior " +
                             std::to_string(raw.ni) + " (illum " + std::to_string(raw.illum) +
                             " with Ni); give a dielectric material in the scene file to be sure");
      if (!raw.map_kd.empty())
        out.warnings.push_back(raw.map_kd_where + ": map_Kd ignored: material \"" + raw.name +
                               "\" is a dielectric, which has no diffuse colour");
    } else if (raw.has_d && raw.d < 1) {
      if (transparency_model || raw.illum < 0) {
        m.opacity = raw.d;
        if (raw.illum < 0)
          out.warnings.push_back(raw.where + ": material \"" + raw.name + "\": d " + std::to_string(raw.d) +
                                 " without illum taken as an opacity (a cut-out letting " +
                                 std::to_string(1 - raw.d) + " of the light through)");
      } else {
        out.warnings.push_back(raw.where + ": material \"" + raw.name + "\": d " + std::to_string(raw.d) +
                               " ignored: illum " + std::to_string(raw.illum) +
                               " has no transparency (the material is opaque)");
      }
    }
    if (!glass && !raw.map_d.empty()) {
      out.opacity_texture = raw.map_d;
      out.opacity_texture_where = raw.map_d_where;
      out.opacity_texture_wrap = raw.map_d_wrap;
    }
    bool emits = raw.ke.x > 0 || raw.ke.y > 0 || raw.ke.z > 0;
    if (emits && (m.opacity < 1 || !out.opacity_texture.empty())) {
      out.warnings.push_back(raw.where + ": material \"" + raw.name +
                             "\": its opacity (d, map_d) is ignored: an emitter cannot be a cut-out");
      m.opacity = 1;
      out.opacity_texture.clear();
    }
    if (glass) {
      // the dielectric above
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
