// Mitsuba 0.6 and 3 XML scene files as pathcl scenes (scene/scene_import.h). Two steps: the XML is read
// into Mitsuba's object graph (objects with named parameters; includes, defaults, $substitutions and
// references resolved; the names of 0.6 files upgraded as Mitsuba 3 upgrades them), which is then
// translated plugin by plugin into the JSON document of docs/scene-format.md. What is exact, what is
// approximated (with a warning) and what is refused: docs/scene-format.md ("Mitsuba XML scenes").
#include <algorithm>
#include <charconv>
#include <cmath>
#include <deque>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <set>
#include <sstream>

#include <glm/glm.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <pugixml.hpp>

#include "scene/scene_error.h"
#include "scene/scene_import.h"
#include "scene/spectrum.h"

namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;

// ---------------------------------------------------------------------------------------------------
// Source files and places

// One XML file of the scene: the main file or an included one.
struct SourceFile {
  std::string path;  // as messages name it
  std::string text;
  std::vector<size_t> line_starts;  // the offset of each line's first byte
  bool upgraded = false;            // version < 2 (Mitsuba 0.6): parameter names upgraded

  int line_at(ptrdiff_t offset) const {
    size_t at = offset < 0 ? 0 : size_t(offset);
    return int(std::upper_bound(line_starts.begin(), line_starts.end(), at) - line_starts.begin());
  }
};

struct Place {
  const SourceFile* file = nullptr;
  int line = 0;
  std::string str() const { return file->path + ":" + std::to_string(line); }
};

[[noreturn]] void fail(const Place& at, const std::string& what) { throw SceneError(at.str() + ": " + what); }

std::string quote(const std::string& s) { return "\"" + s + "\""; }

std::string lower(std::string s) {
  for (char& c : s) c = char(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

// ---------------------------------------------------------------------------------------------------
// Mitsuba's object graph

struct Spectrum {
  std::vector<double> wavelengths, values;  // a uniform spectrum: no wavelengths, one value
  bool uniform() const { return wavelengths.empty(); }
};

enum class Kind { number, integer, boolean, text, vector, rgb, spectrum, blackbody, transform, object, reference };

// One parameter of an object: a value (<float name="alpha" value="0.1"/>), a nested object or a <ref>.
struct Property {
  std::string name;  // empty for a nested object without a name
  Kind kind = Kind::number;
  std::string tag;  // the element, for messages: "float", "rgb", "bsdf", ...
  Place place;
  double number = 0;  // number, integer; blackbody: the temperature in kelvin
  long long integer = 0;
  bool boolean = false;
  std::string text;   // text; reference: the id
  glm::dvec3 vec{0};  // point, vector, rgb; blackbody: (scale, 0, 0)
  Spectrum spectrum;
  glm::dmat4 matrix{1.0};
  size_t object = 0;          // index into Document::objects
  mutable bool used = false;  // read by the translation: the rest is named in a warning
};

struct Object {
  size_t index = 0;
  std::string tag, type, id;  // <bsdf type="diffuse" id="white">
  Place place;
  std::vector<Property> props;

  std::string label() const {
    std::string s = tag == "scene" ? "scene" : tag + " " + quote(type);
    return id.empty() ? s : s + " (id " + quote(id) + ")";
  }
};

struct Document {
  std::deque<SourceFile> files;  // a deque: places point into it
  std::vector<Object> objects;   // objects[0] is the scene
  std::map<std::string, size_t> ids;
  std::vector<std::pair<std::string, std::string>> defaults;  // <default name value>, as ("$name", value)
  std::vector<fs::path> resource_dirs;                        // <path value>, the latest first
  std::vector<std::string> include_chain;                     // the files being read, for include cycles
  std::vector<fs::path> include_keys;                         // the same, canonical
  int depth = 0;                                              // objects nested, while reading
};

// Objects nest a few levels in real scenes (a texture in a bsdf in a twosided in a shape); far deeper
// nesting, or a cycle of references, is refused before it exhausts the stack.
constexpr int kMaxNesting = 64;

const std::set<std::string> kObjectTags = {"sensor", "film",    "sampler", "rfilter", "integrator", "shape",
                                           "bsdf",   "emitter", "texture", "medium",  "phase",      "volume"};

// ---------------------------------------------------------------------------------------------------
// Numbers and words in attribute values

std::string_view trim(std::string_view s) {
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.front()))) s.remove_prefix(1);
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.back()))) s.remove_suffix(1);
  return s;
}

std::optional<double> parse_double(std::string_view s) {
  s = trim(s);
  if (!s.empty() && s.front() == '+') s.remove_prefix(1);
  double v = 0;
  auto [end, error] = std::from_chars(s.data(), s.data() + s.size(), v);
  if (s.empty() || error != std::errc() || end != s.data() + s.size() || !std::isfinite(v)) return std::nullopt;
  return v;
}

// Mitsuba separates the numbers of a list by white space or commas.
std::vector<std::string> split_list(std::string_view s) {
  std::vector<std::string> out;
  std::string word;
  for (char c : s) {
    if (std::isspace(static_cast<unsigned char>(c)) || c == ',') {
      if (!word.empty()) out.push_back(word);
      word.clear();
    } else {
      word += c;
    }
  }
  if (!word.empty()) out.push_back(word);
  return out;
}

double number_or_fail(const Place& at, const std::string& what, std::string_view s) {
  std::optional<double> v = parse_double(s);
  if (!v) fail(at, what + ": could not parse " + quote(std::string(s)) + " as a number");
  return *v;
}

std::vector<double> numbers_or_fail(const Place& at, const std::string& what, std::string_view s) {
  std::vector<double> out;
  for (const std::string& word : split_list(s)) out.push_back(number_or_fail(at, what, word));
  return out;
}

// 0.6's camelCase parameter names in Mitsuba 3's snake_case ("intIOR" -> "int_ior", "toWorld" ->
// "to_world"), as Mitsuba 3 upgrades files of version < 2.
std::string snake_case(const std::string& name) {
  std::string out;
  for (size_t i = 0; i < name.size(); ++i) {
    char c = name[i];
    if (i > 0 && std::islower(static_cast<unsigned char>(name[i - 1])) && std::isupper(static_cast<unsigned char>(c))) {
      out += '_';
      out += char(std::tolower(static_cast<unsigned char>(c)));
      while (i + 1 < name.size() && std::isupper(static_cast<unsigned char>(name[i + 1])))
        out += char(std::tolower(static_cast<unsigned char>(name[++i])));
    } else {
      out += c;
    }
  }
  return out;
}

double srgb_to_linear(double c) { return c <= 0.04045 ? c / 12.92 : std::pow((c + 0.055) / 1.055, 2.4); }

// ---------------------------------------------------------------------------------------------------
// Reading the XML

using Attributes = std::vector<std::pair<std::string, std::string>>;

const std::string* attribute(const Attributes& a, const std::string& name) {
  for (const auto& [key, value] : a)
    if (key == name) return &value;
  return nullptr;
}

std::string attribute_or(const Attributes& a, const std::string& name, const std::string& fallback) {
  const std::string* v = attribute(a, name);
  return v ? *v : fallback;
}

std::string word_list(const std::vector<std::string>& words) {
  std::string s;
  for (size_t i = 0; i < words.size(); ++i) s += (i == 0 ? "" : i + 1 == words.size() ? " and " : ", ") + words[i];
  return s;
}

// Every attribute of <tag> must be in `allowed`, and those of `required` present (as Mitsuba checks).
void expect_attributes(const Place& at, const std::string& tag, const Attributes& a,
                       const std::vector<std::string>& allowed, const std::vector<std::string>& required = {}) {
  for (const auto& [key, value] : a)
    if (std::find(allowed.begin(), allowed.end(), key) == allowed.end())
      fail(at, "unexpected attribute " + quote(key) + " on <" + tag + "> (expected " + word_list(allowed) + ")");
  for (const std::string& key : required)
    if (!attribute(a, key)) fail(at, "<" + tag + "> needs a " + quote(key) + " attribute");
}

Place place_of(const SourceFile& file, pugi::xml_node node) { return {&file, file.line_at(node.offset_debug())}; }

// The node's attributes with $name replaced by the <default>s read so far (the longest names first, as
// Mitsuba does; \$ is a literal $).
Attributes substituted_attributes(const Document& doc, const Place& at, pugi::xml_node node) {
  std::vector<std::pair<std::string, std::string>> defaults = doc.defaults;
  std::stable_sort(defaults.begin(), defaults.end(),
                   [](const auto& a, const auto& b) { return a.first.size() > b.first.size(); });
  Attributes out;
  for (pugi::xml_attribute attr : node.attributes()) {
    std::string value = attr.value();
    if (value.find('$') != std::string::npos) {
      for (const auto& [key, replacement] : defaults)
        for (size_t pos = value.find(key); pos != std::string::npos; pos = value.find(key, pos)) {
          if (pos > 0 && value[pos - 1] == '\\') {
            pos += key.size();
            continue;
          }
          value.replace(pos, key.size(), replacement);
          pos += replacement.size();
          // Defaults that name defaults can grow a value exponentially.
          if (value.size() > (1u << 20))
            fail(at, "attribute " + quote(attr.name()) + " grows beyond 1 MiB by $substitution");
        }
      for (size_t pos = value.find('$'); pos != std::string::npos; pos = value.find('$', pos + 1)) {
        if (pos > 0 && value[pos - 1] == '\\') continue;
        size_t end = pos + 1;
        while (end < value.size() && (std::isalnum(static_cast<unsigned char>(value[end])) || value[end] == '_')) ++end;
        std::string name = value.substr(pos + 1, end - pos - 1);
        fail(at, "undefined parameter $" + name + " in attribute " + quote(attr.name()) +
                     " (expected a <default name=" + quote(name) + " value=\"...\"/> before it)");
      }
      for (size_t pos = value.find("\\$"); pos != std::string::npos; pos = value.find("\\$", pos + 1))
        value.erase(pos, 1);
    }
    out.emplace_back(attr.name(), value);
  }
  return out;
}

void no_children(const Place& at, const std::string& tag, pugi::xml_node node) {
  for (pugi::xml_node child : node.children())
    if (child.type() == pugi::node_element)
      fail(at, "<" + std::string(child.name()) + "> cannot occur inside <" + tag + ">");
}

void add_property(Document& doc, size_t parent, Property p) {
  const Object& o = doc.objects[parent];
  // 0.6's diffuse called its colour diffuseReflectance (Mitsuba 3's upgrade renames it too).
  if (o.place.file && o.place.file->upgraded && o.tag == "bsdf" && o.type == "diffuse" &&
      p.name == "diffuse_reflectance")
    p.name = "reflectance";
  if (!p.name.empty())
    for (const Property& q : o.props)
      if (q.name == p.name)
        fail(p.place, o.label() + ": parameter " + quote(p.name) + " is given twice (first at " + q.place.str() + ")");
  doc.objects[parent].props.push_back(std::move(p));
}

// x, y, z of <translate>, <scale>, <rotate>, <point> and <vector>: from "value" (one number for all three,
// or three) or from x, y and z, each `fallback` when absent.
glm::dvec3 xyz(const Place& at, const std::string& tag, const Attributes& a, double fallback) {
  const std::string* value = attribute(a, "value");
  if (value) {
    if (attribute(a, "x") || attribute(a, "y") || attribute(a, "z"))
      fail(at, "<" + tag + "> cannot mix \"value\" with \"x\", \"y\" or \"z\"");
    std::vector<double> v = numbers_or_fail(at, "<" + tag + ">", *value);
    if (v.size() == 1) return glm::dvec3(v[0]);
    if (v.size() != 3) fail(at, "<" + tag + "> value: expected 1 or 3 numbers, got " + std::to_string(v.size()));
    return {v[0], v[1], v[2]};
  }
  glm::dvec3 out(fallback);
  for (int i = 0; i < 3; ++i)
    if (const std::string* c = attribute(a, std::string(1, char('x' + i))))
      out[i] = number_or_fail(at, "<" + tag + ">", *c);
  return out;
}

glm::dvec3 vector_value(const Place& at, const std::string& tag, const std::string& text) {
  std::vector<double> v = numbers_or_fail(at, "<" + tag + ">", text);
  if (v.size() != 3) fail(at, "<" + tag + ">: expected 3 numbers, got " + std::to_string(v.size()));
  return {v[0], v[1], v[2]};
}

// The first vector of an orthonormal basis around unit n (Duff et al. 2017), as Mitsuba's
// coordinate_system: the up vector of a <lookat> without one.
glm::dvec3 basis_first_vector(glm::dvec3 n) {
  double sign = std::copysign(1.0, n.z), a = -1.0 / (sign + n.z), b = n.x * n.y * a;
  return {1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x};
}

glm::dmat4 look_at(const Place& at, glm::dvec3 origin, glm::dvec3 target, glm::dvec3 up) {
  glm::dvec3 dir = glm::normalize(target - origin);
  if (up == glm::dvec3(0)) up = basis_first_vector(dir);
  glm::dvec3 left = glm::normalize(glm::cross(up, dir));
  glm::dvec3 new_up = glm::cross(dir, left);
  glm::dmat4 m(1.0);
  m[0] = glm::dvec4(left, 0);
  m[1] = glm::dvec4(new_up, 0);
  m[2] = glm::dvec4(dir, 0);
  m[3] = glm::dvec4(origin, 1);
  for (int c = 0; c < 4; ++c)
    for (int r = 0; r < 4; ++r)
      if (!std::isfinite(m[c][r]))
        fail(at, "<lookat>: origin and target coincide, or up is parallel to the view direction");
  return m;
}

// A <transform>'s operations composed in document order, each applied after the ones before it.
glm::dmat4 parse_transform(const Document& doc, const SourceFile& file, pugi::xml_node node) {
  glm::dmat4 m(1.0);
  for (pugi::xml_node op : node.children()) {
    if (op.type() != pugi::node_element) continue;
    const Place at = place_of(file, op);
    const Attributes a = substituted_attributes(doc, at, op);
    std::string tag = op.name();
    if (file.upgraded && tag == "lookAt") tag = "lookat";
    no_children(at, tag, op);
    glm::dmat4 step(1.0);
    if (tag == "translate") {
      expect_attributes(at, tag, a, {"x", "y", "z", "value"});
      step = glm::translate(glm::dmat4(1.0), xyz(at, tag, a, 0));
    } else if (tag == "scale") {
      expect_attributes(at, tag, a, {"x", "y", "z", "value"});
      step = glm::scale(glm::dmat4(1.0), xyz(at, tag, a, 1));
    } else if (tag == "rotate") {
      expect_attributes(at, tag, a, {"x", "y", "z", "value", "angle"}, {"angle"});
      glm::dvec3 axis = xyz(at, tag, a, 0);
      if (axis == glm::dvec3(0)) fail(at, "<rotate>: the rotation axis is zero");
      double angle = number_or_fail(at, "<rotate> angle", *attribute(a, "angle"));
      step = glm::rotate(glm::dmat4(1.0), glm::radians(angle), axis);
    } else if (tag == "lookat") {
      expect_attributes(at, tag, a, {"origin", "target", "up"}, {"origin", "target"});
      glm::dvec3 up = attribute(a, "up") ? vector_value(at, "lookat up", *attribute(a, "up")) : glm::dvec3(0);
      step = look_at(at, vector_value(at, "lookat origin", *attribute(a, "origin")),
                     vector_value(at, "lookat target", *attribute(a, "target")), up);
    } else if (tag == "matrix") {
      expect_attributes(at, tag, a, {"value"}, {"value"});
      std::vector<double> v = numbers_or_fail(at, "<matrix>", *attribute(a, "value"));
      if (v.size() != 16 && v.size() != 9)
        fail(at, "<matrix>: expected 16 (or 9) numbers, got " + std::to_string(v.size()));
      int n = v.size() == 16 ? 4 : 3;
      for (int r = 0; r < n; ++r)
        for (int c = 0; c < n; ++c) step[c][r] = v[size_t(r * n + c)];  // written row by row
      if (n == 4 && (step[0][3] != 0 || step[1][3] != 0 || step[2][3] != 0 || step[3][3] != 1))
        fail(at, "<matrix>: the last row must be 0 0 0 1 (an affine transform)");
    } else {
      fail(at, "<" + tag + "> cannot occur inside <transform> (expected translate, rotate, scale, lookat or matrix)");
    }
    m = step * m;
  }
  return m;
}

// The (wavelength, value) pairs of a .spd file: two columns, '#' comments.
Spectrum read_spectrum_file(const Place& at, const fs::path& path, const std::string& shown) {
  std::ifstream in(path);
  if (!in) fail(at, "<spectrum filename=" + quote(shown) + ">: cannot open the spectrum file " + path.generic_string());
  Spectrum s;
  std::string line;
  for (int number = 1; std::getline(in, line); ++number) {
    std::string_view t = trim(line);
    if (t.empty() || t.front() == '#') continue;
    std::vector<std::string> words = split_list(t);
    std::optional<double> wl = words.size() == 2 ? parse_double(words[0]) : std::nullopt;
    std::optional<double> v = words.size() == 2 ? parse_double(words[1]) : std::nullopt;
    if (!wl || !v)
      throw SceneError(path.generic_string() + ":" + std::to_string(number) +
                       ": expected two columns, a wavelength in nm and a value (read from " + at.str() + ")");
    s.wavelengths.push_back(*wl);
    s.values.push_back(*v);
  }
  return s;
}

void check_spectrum(const Place& at, const Spectrum& s) {
  if (s.wavelengths.size() < 2)
    fail(at, "<spectrum>: expected at least two wavelength:value pairs (or one uniform value)");
  for (size_t i = 1; i < s.wavelengths.size(); ++i)
    if (!(s.wavelengths[i] > s.wavelengths[i - 1]))
      fail(at, "<spectrum>: the wavelengths must increase (" + std::to_string(s.wavelengths[i]) + " after " +
                   std::to_string(s.wavelengths[i - 1]) + ")");
}

// <spectrum value="0.5"/> (uniform) or value="400:0.1, 500:0.3, ...".
Spectrum parse_spectrum_value(const Place& at, const std::string& text) {
  std::vector<std::string> words = split_list(text);
  Spectrum s;
  if (words.size() == 1 && words[0].find(':') == std::string::npos) {
    s.values.push_back(number_or_fail(at, "<spectrum>", words[0]));
    return s;
  }
  for (const std::string& w : words) {
    size_t colon = w.find(':');
    if (colon == std::string::npos) fail(at, "<spectrum>: expected wavelength:value pairs, got " + quote(w));
    s.wavelengths.push_back(number_or_fail(at, "<spectrum> wavelength", w.substr(0, colon)));
    s.values.push_back(number_or_fail(at, "<spectrum> value", w.substr(colon + 1)));
  }
  check_spectrum(at, s);
  return s;
}

// A file named in the scene (a spectrum, an include): relative to the file that names it, then to the
// <path> directories.
fs::path find_file(const Document& doc, const SourceFile& file, const std::string& name) {
  fs::path p(name);
  if (p.is_absolute()) return p;
  fs::path here = fs::path(file.path).parent_path() / p;
  std::error_code ignored;
  if (fs::exists(here, ignored)) return here;
  for (const fs::path& dir : doc.resource_dirs)
    if (fs::exists(dir / p, ignored)) return dir / p;
  return here;
}

void parse_element(Document& doc, const SourceFile& file, pugi::xml_node node, size_t parent, bool file_root = false,
                   const std::string& include_name = "");
void parse_file(Document& doc, const std::string& path, std::string text, std::optional<size_t> parent,
                const std::string& include_name);

void parse_children(Document& doc, const SourceFile& file, pugi::xml_node node, size_t parent) {
  for (pugi::xml_node child : node.children()) parse_element(doc, file, child, parent);
}

void parse_include(Document& doc, const SourceFile& file, const Place& at, const Attributes& a, size_t parent) {
  expect_attributes(at, "include", a, {"filename", "name"}, {"filename"});
  const std::string& name = *attribute(a, "filename");
  const std::string what = "<include filename=" + quote(name) + ">";
  fs::path path = find_file(doc, file, name);
  const std::string shown = path.lexically_normal().generic_string();
  std::error_code error;
  fs::path key = fs::weakly_canonical(path, error);
  if (error) key = fs::absolute(path).lexically_normal();
  for (size_t i = 0; i < doc.include_keys.size(); ++i)
    if (doc.include_keys[i] == key) {
      std::string chain;
      for (size_t j = i; j < doc.include_chain.size(); ++j) chain += doc.include_chain[j] + " includes ";
      fail(at, what + ": an include cycle (" + chain + shown + " again)");
    }
  if (doc.include_chain.size() >= 64) fail(at, what + ": includes nested more than 64 deep");
  if (fs::is_directory(path, error)) fail(at, what + ": " + shown + " is a directory, expected an XML file");
  std::ifstream in(path, std::ios::binary);
  if (!in)
    fail(at, what + ": cannot open the included file " + shown + (fs::exists(path, error) ? "" : ": no such file"));
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  doc.include_chain.push_back(shown);
  doc.include_keys.push_back(key);
  parse_file(doc, shown, std::move(text), parent, attribute_or(a, "name", ""));
  doc.include_chain.pop_back();
  doc.include_keys.pop_back();
}

void parse_object(Document& doc, const SourceFile& file, pugi::xml_node node, size_t parent, const Place& at,
                  const std::string& tag, const Attributes& a, const std::string& name, bool file_root) {
  std::vector<std::string> allowed = {"type", "id", "name"};
  if (file_root) allowed.push_back("version");
  expect_attributes(at, tag, a, allowed, {"type"});
  Object o;
  o.index = doc.objects.size();
  o.tag = tag;
  o.type = *attribute(a, "type");
  o.id = attribute_or(a, "id", "");
  o.place = at;
  if (!o.id.empty()) {
    auto [it, inserted] = doc.ids.emplace(o.id, o.index);
    if (!inserted) fail(at, "duplicate id " + quote(o.id) + " (first at " + doc.objects[it->second].place.str() + ")");
  }
  Property p;
  p.name = name;
  p.kind = Kind::object;
  p.tag = tag;
  p.place = at;
  p.object = o.index;
  const size_t index = o.index;
  doc.objects.push_back(std::move(o));
  add_property(doc, parent, std::move(p));
  if (++doc.depth > kMaxNesting) fail(at, "objects nested more than " + std::to_string(kMaxNesting) + " deep");
  parse_children(doc, file, node, index);
  --doc.depth;
}

void parse_element(Document& doc, const SourceFile& file, pugi::xml_node node, size_t parent, bool file_root,
                   const std::string& include_name) {
  if (node.type() != pugi::node_element) return;
  const Place at = place_of(file, node);
  const Attributes a = substituted_attributes(doc, at, node);
  std::string tag = node.name();
  if (file.upgraded && tag == "lookAt") tag = "lookat";
  std::string name = attribute_or(a, "name", include_name);
  if (file.upgraded && tag != "default") name = snake_case(name);

  if (kObjectTags.count(tag) || (tag == "spectrum" && attribute(a, "type"))) {
    parse_object(doc, file, node, parent, at, tag, a, name, file_root);
    return;
  }
  if (tag == "scene") fail(at, "<scene> can only be the root element");
  if (file_root)
    fail(at, "the root element <" + tag + "> is not an object (expected <scene> or an object such as <bsdf>)");

  if (tag != "transform") no_children(at, tag, node);
  if (tag == "include") return parse_include(doc, file, at, a, parent);
  if (tag == "default") {
    expect_attributes(at, tag, a, {"name", "value"}, {"name", "value"});
    if (name.empty()) fail(at, "<default>: the name is empty");
    bool known =
        std::any_of(doc.defaults.begin(), doc.defaults.end(), [&](const auto& d) { return d.first == "$" + name; });
    if (!known) doc.defaults.emplace_back("$" + name, *attribute(a, "value"));
    return;
  }
  if (tag == "alias") {
    expect_attributes(at, tag, a, {"id", "as"}, {"id", "as"});
    auto it = doc.ids.find(*attribute(a, "id"));
    if (it == doc.ids.end()) fail(at, "<alias>: no object has the id " + quote(*attribute(a, "id")));
    if (!doc.ids.emplace(*attribute(a, "as"), it->second).second)
      fail(at, "<alias>: the id " + quote(*attribute(a, "as")) + " is taken");
    return;
  }
  if (tag == "path") {
    expect_attributes(at, tag, a, {"value"}, {"value"});
    doc.resource_dirs.insert(doc.resource_dirs.begin(), fs::path(file.path).parent_path() / *attribute(a, "value"));
    return;
  }

  Property p;
  p.name = name;
  p.tag = tag;
  p.place = at;
  const std::string what = "<" + tag + " name=" + quote(name) + ">";
  if (tag == "ref") {
    expect_attributes(at, tag, a, {"id", "name"}, {"id"});
    p.kind = Kind::reference;
    p.text = *attribute(a, "id");
    return add_property(doc, parent, std::move(p));
  }
  if (tag == "transform") {
    expect_attributes(at, tag, a, {"name"}, {"name"});
    p.kind = Kind::transform;
    p.matrix = parse_transform(doc, file, node);
    return add_property(doc, parent, std::move(p));
  }
  // 0.6 files may say how a colour is meant ("reflectance", "illuminant"); it changes nothing in RGB.
  std::vector<std::string> intent = file.upgraded ? std::vector<std::string>{"intent"} : std::vector<std::string>{};
  auto allowed = [&](std::vector<std::string> names) {
    names.insert(names.end(), intent.begin(), intent.end());
    return names;
  };
  if (tag == "float") {
    expect_attributes(at, tag, a, {"name", "value"}, {"name", "value"});
    p.kind = Kind::number;
    p.number = number_or_fail(at, what, *attribute(a, "value"));
  } else if (tag == "integer") {
    expect_attributes(at, tag, a, {"name", "value"}, {"name", "value"});
    std::string_view v = trim(*attribute(a, "value"));
    auto [end, error] = std::from_chars(v.data(), v.data() + v.size(), p.integer);
    if (v.empty() || error != std::errc() || end != v.data() + v.size())
      fail(at, what + ": could not parse " + quote(*attribute(a, "value")) + " as an integer");
    p.kind = Kind::integer;
    p.number = double(p.integer);
  } else if (tag == "boolean") {
    expect_attributes(at, tag, a, {"name", "value"}, {"name", "value"});
    std::string v = lower(*attribute(a, "value"));
    if (v != "true" && v != "false") fail(at, what + ": expected true or false, got " + quote(*attribute(a, "value")));
    p.kind = Kind::boolean;
    p.boolean = v == "true";
  } else if (tag == "string") {
    expect_attributes(at, tag, a, {"name", "value"}, {"name", "value"});
    p.kind = Kind::text;
    p.text = *attribute(a, "value");
  } else if (tag == "point" || tag == "vector") {
    expect_attributes(at, tag, a, {"name", "value", "x", "y", "z"}, {"name"});
    if (!attribute(a, "value") && (!attribute(a, "x") || !attribute(a, "y") || !attribute(a, "z")))
      fail(at, what + ": expected x, y and z (or value)");
    p.kind = Kind::vector;
    p.vec = xyz(at, tag, a, 0);
  } else if (tag == "rgb" || tag == "srgb") {
    expect_attributes(at, tag, a, allowed({"name", "value"}), {"name", "value"});
    const std::string& v = *attribute(a, "value");
    p.kind = Kind::rgb;
    if (tag == "srgb" && !v.empty() && v[0] == '#') {  // 0.6: "#rrggbb"
      unsigned value = 0;
      auto [end, error] = std::from_chars(v.data() + 1, v.data() + v.size(), value, 16);
      if (v.size() != 7 || error != std::errc() || end != v.data() + v.size())
        fail(at, what + ": expected #rrggbb, got " + quote(v));
      p.vec = glm::dvec3((value >> 16) & 255, (value >> 8) & 255, value & 255) / 255.0;
    } else {
      std::vector<double> c = numbers_or_fail(at, what, v);
      if (c.size() != 1 && c.size() != 3) fail(at, what + ": expected 1 or 3 numbers, got " + std::to_string(c.size()));
      p.vec = c.size() == 1 ? glm::dvec3(c[0]) : glm::dvec3(c[0], c[1], c[2]);
    }
    if (tag == "srgb")  // 0.6's gamma-encoded sRGB
      for (int i = 0; i < 3; ++i) p.vec[i] = srgb_to_linear(p.vec[i]);
  } else if (tag == "spectrum") {
    expect_attributes(at, tag, a, allowed({"name", "value", "filename"}), {"name"});
    if (bool(attribute(a, "value")) == bool(attribute(a, "filename")))
      fail(at, what + ": expected either a value or a filename attribute");
    p.kind = Kind::spectrum;
    if (attribute(a, "value")) {
      p.spectrum = parse_spectrum_value(at, *attribute(a, "value"));
    } else {
      const std::string& filename = *attribute(a, "filename");
      p.spectrum = read_spectrum_file(at, find_file(doc, file, filename), filename);
      check_spectrum(at, p.spectrum);
    }
  } else if (tag == "blackbody") {  // 0.6: <blackbody name="intensity" temperature="5000K" scale="1"/>
    expect_attributes(at, tag, a, allowed({"name", "temperature", "scale"}), {"name", "temperature"});
    std::string t = *attribute(a, "temperature");
    if (!t.empty() && (t.back() == 'K' || t.back() == 'k')) t.pop_back();
    p.kind = Kind::blackbody;
    p.number = number_or_fail(at, what + " temperature", t);
    if (!(p.number > 0)) fail(at, what + ": expected a temperature > 0 kelvin");
    p.vec = glm::dvec3(attribute(a, "scale") ? number_or_fail(at, what + " scale", *attribute(a, "scale")) : 1.0, 0, 0);
  } else if (tag == "translate" || tag == "rotate" || tag == "scale" || tag == "lookat" || tag == "matrix") {
    fail(at, "<" + tag + "> can only occur inside <transform>");
  } else {
    fail(at, "unknown element <" + tag + ">");
  }
  add_property(doc, parent, std::move(p));
}

// The version's major number: 0.6 files (below 2) have their names upgraded.
int version_major(const Place& at, const std::string& tag, const std::string& version) {
  std::vector<std::string> parts;
  std::stringstream s(version);
  for (std::string part; std::getline(s, part, '.');) parts.push_back(part);
  bool valid = !parts.empty() && parts.size() <= 3;
  for (const std::string& part : parts)
    valid = valid && !part.empty() &&
            std::all_of(part.begin(), part.end(), [](char c) { return std::isdigit(static_cast<unsigned char>(c)); });
  if (!valid) fail(at, "<" + tag + "> version " + quote(version) + ": expected major.minor.patch, e.g. \"3.0.0\"");
  return parts[0].size() > 3 ? 999 : std::stoi(parts[0]);
}

void parse_file(Document& doc, const std::string& path, std::string text, std::optional<size_t> parent,
                const std::string& include_name) {
  SourceFile& file = doc.files.emplace_back();
  file.path = path;
  file.text = std::move(text);
  file.line_starts.push_back(0);
  for (size_t i = 0; i < file.text.size(); ++i)
    if (file.text[i] == '\n') file.line_starts.push_back(i + 1);
  pugi::xml_document xml;
  pugi::xml_parse_result result = xml.load_buffer(file.text.data(), file.text.size());
  if (!result) fail({&file, file.line_at(result.offset)}, std::string("malformed XML: ") + result.description());
  pugi::xml_node root = xml.document_element();
  if (!root) fail({&file, 1}, "malformed XML: no root element (expected <scene version=\"...\">)");
  const Place at = place_of(file, root);
  const std::string tag = root.name();
  pugi::xml_attribute version = root.attribute("version");
  if (!version)
    fail(at,
         "<" + tag + "> has no version attribute (Mitsuba requires one: <" + tag + " version=\"3.0.0\"> or \"0.6.0\")");
  file.upgraded = version_major(at, tag, version.value()) < 2;
  if (!parent) {
    if (tag != "scene") fail(at, "the root element is <" + tag + ">, expected <scene version=\"...\">");
    expect_attributes(at, tag, substituted_attributes(doc, at, root), {"version", "type", "id", "name"});
    Object scene;
    scene.tag = scene.type = "scene";
    scene.place = at;
    doc.objects.push_back(std::move(scene));
    parse_children(doc, file, root, 0);
  } else if (tag == "scene") {  // an included scene: its objects join the including element
    expect_attributes(at, tag, substituted_attributes(doc, at, root), {"version", "type", "id", "name"});
    parse_children(doc, file, root, *parent);
  } else {  // an included object: one parameter of the including element
    parse_element(doc, file, root, *parent, true, include_name);
  }
}

// ---------------------------------------------------------------------------------------------------
// The translation: its state, and reading an object's parameters

struct MaterialInfo {
  std::string name;
  bool one_sided = false;   // Mitsuba reflects on the front side only (no twosided around it)
  bool dielectric = false;  // its two sides differ in pathcl too
  bool textured = false;    // reads texture coordinates
};

struct Importer {
  Document doc;
  ImportedScene out;
  std::set<std::string> warned;
  fs::path scene_dir;
  json materials = json::object(), shapes = json::array(), lights = json::array();
  std::map<size_t, MaterialInfo> material_of;            // by bsdf object
  std::map<std::string, MaterialInfo> default_material;  // Mitsuba's default bsdfs, by kind
  std::set<std::string> names;                           // material names taken, bsdf ids included
  bool environment = false;
  int depth = 0;  // bsdfs and textures being translated, one inside the other
  std::set<size_t> attached_emitters;  // area emitters that shapes took, by object

  // A warning once, however often the object it is about is used.
  void warn(const Place& at, const std::string& what) {
    std::string message = at.str() + ": " + what;
    if (warned.insert(message).second) out.warnings.push_back(message);
  }
  void origin(const std::string& json_path, const Object& o) {
    out.origins.emplace_back(json_path, o.place.str() + ": " + o.label());
  }
};

const Property* find(const Object& o, const std::string& name) {
  for (const Property& p : o.props)
    if (p.name == name) {
      p.used = true;
      return &p;
    }
  return nullptr;
}

// Parameters that pathcl's translation does not need: they choose an output format or steer sampling
// without changing the expected image (docs/scene-format.md ("Mitsuba XML scenes") lists them).
void consume(const Object& o, std::initializer_list<const char*> names) {
  for (const char* name : names) find(o, name);
}

[[noreturn]] void wrong_kind(const Object& o, const Property& p, const std::string& expected) {
  fail(p.place, o.label() + ": parameter " + quote(p.name) + " is a <" + p.tag + ">, expected " + expected);
}

std::optional<double> optional_number(const Object& o, const std::string& name) {
  const Property* p = find(o, name);
  if (!p) return std::nullopt;
  if (p->kind != Kind::number && p->kind != Kind::integer) wrong_kind(o, *p, "a <float>");
  return p->number;
}

double number(const Object& o, const std::string& name, double fallback) {
  return optional_number(o, name).value_or(fallback);
}

std::optional<long long> optional_integer(const Object& o, const std::string& name) {
  const Property* p = find(o, name);
  if (!p) return std::nullopt;
  if (p->kind != Kind::integer) wrong_kind(o, *p, "an <integer>");
  return p->integer;
}

long long integer(const Object& o, const std::string& name, long long fallback) {
  return optional_integer(o, name).value_or(fallback);
}

bool boolean(const Object& o, const std::string& name, bool fallback) {
  const Property* p = find(o, name);
  if (!p) return fallback;
  if (p->kind != Kind::boolean) wrong_kind(o, *p, "a <boolean>");
  return p->boolean;
}

std::optional<std::string> optional_text(const Object& o, const std::string& name) {
  const Property* p = find(o, name);
  if (!p) return std::nullopt;
  if (p->kind != Kind::text) wrong_kind(o, *p, "a <string>");
  return p->text;
}

std::string text(const Object& o, const std::string& name, const std::string& fallback) {
  return optional_text(o, name).value_or(fallback);
}

std::optional<glm::dvec3> optional_vector(const Object& o, const std::string& name) {
  const Property* p = find(o, name);
  if (!p) return std::nullopt;
  if (p->kind != Kind::vector) wrong_kind(o, *p, "a <point> or <vector>");
  return p->vec;
}

glm::dmat4 transform(const Object& o, const std::string& name) {
  const Property* p = find(o, name);
  if (!p) return glm::dmat4(1.0);
  if (p->kind != Kind::transform) wrong_kind(o, *p, "a <transform>");
  return p->matrix;
}

// Where a message about a parameter belongs: the parameter's line, else its object's.
Place place_of(const Object& o, const std::string& name) {
  for (const Property& p : o.props)
    if (p.name == name) return p.place;
  return o.place;
}

bool is_object(const Property& p) { return p.kind == Kind::object || p.kind == Kind::reference; }

const Object& resolve(const Importer& im, const Property& p) {
  if (p.kind == Kind::object) return im.doc.objects[p.object];
  auto it = im.doc.ids.find(p.text);
  if (it == im.doc.ids.end()) fail(p.place, "<ref id=" + quote(p.text) + ">: no object has this id");
  return im.doc.objects[it->second];
}

// The objects with this tag nested in o or referenced by its <ref>s, in document order.
std::vector<const Object*> nested(const Importer& im, const Object& o, const std::string& tag) {
  std::vector<const Object*> out;
  for (const Property& p : o.props)
    if (is_object(p)) {
      const Object& child = resolve(im, p);
      if (child.tag == tag) {
        p.used = true;
        out.push_back(&child);
      }
    }
  return out;
}

// Counts the objects being translated inside one another: a <ref> cycle (a bsdf that holds itself) fails
// instead of recursing for ever.
struct NestingGuard {
  Importer& im;
  NestingGuard(Importer& importer, const Object& o) : im(importer) {
    if (++im.depth > kMaxNesting)
      fail(o.place,
           o.label() + ": objects nested more than " + std::to_string(kMaxNesting) + " deep (a cycle of references?)");
  }
  ~NestingGuard() { --im.depth; }
};

// What the translation did not read is named, never dropped silently.
void warn_unused(Importer& im, const Object& o) {
  for (const Property& p : o.props) {
    if (p.used) continue;
    p.used = true;
    if (is_object(p))
      im.warn(p.place, o.label() + ": the nested " + resolve(im, p).label() + " is not used by pathcl; ignored");
    else
      im.warn(p.place, o.label() + ": parameter " + quote(p.name) + " is not supported; ignored");
  }
}

// ---------------------------------------------------------------------------------------------------
// JSON values


std::string format_number(double v, int digits = 4) {
  std::ostringstream s;
  s.precision(digits);
  s << v;
  return s.str();
}

std::string format_color(glm::dvec3 c) {
  std::ostringstream s;
  s.precision(4);
  s << '(' << c.x << ", " << c.y << ", " << c.z << ')';
  return s.str();
}

// A rotation (or a mirrored one) within Mitsuba's tolerance: M M^T = I to 1e-3, as its has_scale() tests.
bool is_orthonormal(const glm::dmat3& m) {
  glm::dmat3 p = m * glm::transpose(m);
  for (int c = 0; c < 3; ++c)
    for (int r = 0; r < 3; ++r)
      if (std::abs(p[c][r] - (c == r ? 1.0 : 0.0)) > 1e-3) return false;
  return true;
}

// A mesh or image file as the scene names it: pathcl resolves it against the scene file's directory, as
// Mitsuba does; one found only in a <path> directory is named through that directory.
std::string scene_file_path(const Importer& im, const std::string& name) {
  fs::path p(name);
  std::error_code ignored;
  if (p.is_absolute() || fs::exists(im.scene_dir / p, ignored)) return name;
  for (const fs::path& dir : im.doc.resource_dirs)
    if (fs::exists(dir / p, ignored))
      return fs::absolute(dir / p).lexically_normal().lexically_relative(fs::absolute(im.scene_dir)).generic_string();
  return name;
}

// ---------------------------------------------------------------------------------------------------
// Colours, spectra and textures, by Mitsuba 3's RGB conventions (mitsuba/core/properties.cpp)

enum class Role {
  reflectance,  // bounded by [0, 1], weighted by D65
  unbounded,    // an index of refraction (eta, k): weighted by D65, not bounded by 1
  emission,     // radiance, intensity, irradiance: not weighted; a uniform spectrum is xyz_to_srgb(1, 1, 1) v
};

// Mitsuba's checkerboard as pathcl's {"checkerboard": {...}} (docs/scene-format.md, Textures): its colours,
// and along each axis the tiles per unit of uv and the offset in tiles (checkerboard() below).
struct Checker {
  glm::dvec3 color0{0.4}, color1{0.2};  // Mitsuba's defaults
  glm::dvec2 tiles{2, 2}, offset{0, 0};
  json to_json() const {
    json c = {{"color0", vec_json(color0)}, {"color1", vec_json(color1)}, {"tiles", {tiles.x, tiles.y}}};
    if (offset != glm::dvec2(0)) c["offset"] = {offset.x, offset.y};
    return {{"checkerboard", c}};
  }
};

// A colour parameter as pathcl takes it: an RGB value, an image ({"texture": FILE, "wrap": MODE}) or a
// checkerboard.
struct Color {
  glm::dvec3 rgb{0};
  json texture;  // an image
  std::optional<Checker> checker;
  bool textured() const { return !texture.is_null() || checker.has_value(); }
  json to_json() const { return checker ? checker->to_json() : textured() ? texture : vec_json(rgb); }
  // f on each constant colour: the colour, or a checkerboard's two (an image's texels are not reached).
  template <class F>
  void each_constant(F f) {
    if (checker) {
      f(checker->color0);
      f(checker->color1);
    } else if (texture.is_null()) {
      f(rgb);
    }
  }
};

glm::dvec3 spectrum_rgb(Importer& im, const Place& at, const Spectrum& s, Role role) {
  if (s.uniform()) return role == Role::emission ? uniform_emission_to_srgb(s.values[0]) : glm::dvec3(s.values[0]);
  bool clamped = false;
  if (role == Role::emission) {
    glm::dvec3 rgb = emission_spectrum_to_srgb(s.wavelengths, s.values, &clamped);
    if (clamped) im.warn(at, "the spectrum's negative sRGB components are clamped to 0 (as Mitsuba clamps them)");
    return rgb;
  }
  if (role == Role::reflectance) {
    glm::dvec3 rgb = reflectance_spectrum_to_srgb(s.wavelengths, s.values, &clamped);
    if (clamped) im.warn(at, "the spectrum's sRGB colour is clamped into [0, 1] (as Mitsuba clamps it)");
    return rgb;
  }
  // The reflectance conversion is linear until it clamps: the spectrum is scaled into its range and the
  // colour scaled back, which leaves only the clamping of negative components (as Mitsuba's).
  double peak = 0;
  for (double v : s.values) peak = std::max(peak, std::abs(v));
  if (peak == 0) return glm::dvec3(0);
  std::vector<double> scaled;
  for (double v : s.values) scaled.push_back(v / (4 * peak));
  return reflectance_spectrum_to_srgb(s.wavelengths, scaled) * (4 * peak);
}

bool is_eight_bit_image(const std::string& file) {
  std::string ext = lower(fs::path(file).extension().string());
  return ext == ".png" || ext == ".jpg" || ext == ".jpeg" || ext == ".bmp" || ext == ".tga";
}

enum class TextureUse { color, opacity };

// A bitmap texture as pathcl's {"texture": FILE, "wrap": MODE}.
json bitmap_json(Importer& im, const Object& t, TextureUse use) {
  std::optional<std::string> filename = optional_text(t, "filename");
  if (!filename) fail(t.place, t.label() + ": needs a filename (pathcl reads textures from image files)");
  const std::string file = scene_file_path(im, *filename);

  std::string wrap = lower(text(t, "wrap_mode", "repeat"));
  if (std::optional<std::string> u = optional_text(t, "wrap_mode_u")) wrap = lower(*u);  // 0.6
  if (std::optional<std::string> v = optional_text(t, "wrap_mode_v"); v && lower(*v) != wrap)
    im.warn(place_of(t, "wrap_mode_v"), t.label() + ": wrap_mode_v " + quote(*v) +
                                            " differs from wrap_mode_u: pathcl wraps both axes as " + quote(wrap));
  if (wrap != "repeat" && wrap != "mirror" && wrap != "clamp")
    fail(place_of(t, "wrap_mode"),
         t.label() + ": wrap mode " + quote(wrap) + " is not supported (expected repeat, mirror or clamp)");

  std::string filter = lower(text(t, "filter_type", "bilinear"));
  if (filter == "nearest")
    im.warn(place_of(t, "filter_type"),
            t.label() + ": nearest-neighbour lookups become bilinear (pathcl filters every texture bilinearly)");
  else if (filter != "bilinear" && filter != "ewa" &&
           filter != "trilinear")  // 0.6's ewa and trilinear prefilter; pathcl's pixels average
    fail(place_of(t, "filter_type"), t.label() + ": filter_type " + quote(filter) + " (expected bilinear or nearest)");

  // Mitsuba decodes 8-bit images from sRGB unless raw (0.6: gamma 1 is linear, -1 sRGB).
  bool raw = boolean(t, "raw", false);
  if (std::optional<double> gamma = optional_number(t, "gamma")) {
    if (*gamma == 1)
      raw = true;
    else if (*gamma != -1)
      im.warn(place_of(t, "gamma"),
              t.label() + ": gamma " + format_number(*gamma) +
                  " is not supported: pathcl decodes 8-bit images from sRGB and reads EXR and HDR images linearly");
  }
  if (is_eight_bit_image(file)) {
    if (use == TextureUse::color && raw)
      im.warn(t.place,
              t.label() + ": pathcl decodes 8-bit colour textures from sRGB; Mitsuba reads this one linearly (raw)");
    if (use == TextureUse::opacity && !raw)
      im.warn(t.place,
              t.label() +
                  ": pathcl reads an 8-bit opacity map linearly; Mitsuba decodes this one from sRGB (raw is false)");
  }
  bool moved = !is_identity(transform(t, "to_uv"), 1e-12);
  for (const char* name : {"uoffset", "voffset"}) moved = moved || number(t, name, 0) != 0;  // 0.6
  for (const char* name : {"uscale", "vscale"}) moved = moved || number(t, name, 1) != 1;
  if (moved)
    im.warn(t.place, t.label() +
                         ": to_uv (the texture's scale and offset) is not supported: the image is placed by the mesh's "
                         "own texture coordinates");
  consume(t, {"accel", "format", "max_anisotropy", "cache"});
  warn_unused(im, t);
  return {{"texture", file}, {"wrap", wrap}};
}

Color read_color(Importer& im, const Object& owner, const Property& p, Role role);

// One axis of a checkerboard: Mitsuba's s = a w + b along it (w the texture coordinate it runs along) as pathcl's
// tiles per unit and offset in tiles, of x = 2 s (Mitsuba's pattern has two tiles per unit of s). A mirrored axis
// (a < 0) counts the tiles the other way: off the tiles' edges floor(-x) = -floor(x) - 1, one tile more of
// offset. Offsets are reduced modulo 2 tiles, the pattern's period.
void checker_axis(double a, double b, double& tiles, double& offset) {
  tiles = 2 * std::abs(a);
  const double o = a > 0 ? 2 * b : 1 - 2 * b;
  offset = o - 2 * std::floor(o / 2);
}

// Mitsuba's checkerboard (src/textures/checkerboard.cpp): at s = to_uv (u, v), color0 where frac(s) > 0.5 along
// both axes or along neither, else color1 (0.4 and 0.2 by default), evaluated at the point. pathcl's checkerboard
// (kernels/texture.cl) counts x = u tiles_u + offset_u and y = (1 - v) tiles_v + offset_v, and its v is Mitsuba's
// 1 - v (the shapes' uvs are written flipped, triangles_json, and mesh files are read as Mitsuba reads them), so
// y runs along Mitsuba's v. to_uv is read as Mitsuba reads a 4 x 4 transform for a 2-D one (Transform::extract):
// the upper-left 2 x 2 block and the first two entries of the translation column; 0.6's uoffset, voffset, uscale
// and vscale as Mitsuba 3 upgrades them (scale times translate). A to_uv that scales, mirrors and translates the
// axes is exact, and so is one that also swaps them (a rotation by a multiple of 90 degrees): the parity of
// floor(x) + floor(y) does not depend on their order. Other rotations and shears are dropped with a warning.
Checker checkerboard(Importer& im, const Object& t) {
  Checker c;
  for (const char* name : {"color0", "color1"}) {
    const Property* p = find(t, name);
    if (!p) continue;
    Color v = read_color(im, t, *p, Role::reflectance);
    if (v.textured())
      fail(p->place, t.label() + ": " + name + " is a texture (pathcl's checkerboard takes two constant colours)");
    (std::string(name) == "color0" ? c.color0 : c.color1) = v.rgb;
  }
  glm::dmat4 m = transform(t, "to_uv");
  std::optional<double> uoffset = optional_number(t, "uoffset"), voffset = optional_number(t, "voffset"),
                        uscale = optional_number(t, "uscale"), vscale = optional_number(t, "vscale");
  if (uoffset || voffset || uscale || vscale)  // 0.6
    m = glm::scale(glm::dmat4(1.0), glm::dvec3(uscale.value_or(1), vscale.value_or(1), 1)) *
        glm::translate(glm::dmat4(1.0), glm::dvec3(uoffset.value_or(0), voffset.value_or(0), 0));
  // s.x = a[0][0] u + a[0][1] v + b[0], s.y = a[1][0] u + a[1][1] v + b[1] (glm's m[column][row]).
  const double a[2][2] = {{m[0][0], m[1][0]}, {m[0][1], m[1][1]}}, b[2] = {m[3][0], m[3][1]};
  const Place at = place_of(t, "to_uv");
  const double largest = std::max({std::abs(a[0][0]), std::abs(a[0][1]), std::abs(a[1][0]), std::abs(a[1][1])});
  auto zero = [&](double v) { return std::abs(v) <= 1e-12 * largest; };  // a rotation's cos 90 degrees is 6e-17
  if (!zero(a[0][0]) && !zero(a[1][1]) && zero(a[0][1]) && zero(a[1][0])) {
    checker_axis(a[0][0], b[0], c.tiles.x, c.offset.x);
    checker_axis(a[1][1], b[1], c.tiles.y, c.offset.y);
  } else if (zero(a[0][0]) && zero(a[1][1]) && !zero(a[0][1]) && !zero(a[1][0])) {  // u and v swapped
    checker_axis(a[1][0], b[1], c.tiles.x, c.offset.x);
    checker_axis(a[0][1], b[0], c.tiles.y, c.offset.y);
  } else {
    const double row0 = std::hypot(a[0][0], a[0][1]), row1 = std::hypot(a[1][0], a[1][1]);
    if (zero(row0) || zero(row1) || largest == 0)
      fail(at, t.label() + ": to_uv maps the texture coordinates onto a line or a point (a zero scale): not supported");
    im.warn(at, t.label() +
                    ": to_uv rotates or shears the pattern, which pathcl's checkerboard cannot (its tiles are aligned "
                    "with u and v): the tiles keep their size, the rotation is dropped");
    checker_axis(row0, b[0], c.tiles.x, c.offset.x);
    checker_axis(row1, b[1], c.tiles.y, c.offset.y);
  }
  warn_unused(im, t);
  return c;
}

// A texture or typed spectrum object (<texture type="bitmap">, <spectrum type="blackbody">, ...).
Color color_object(Importer& im, const Object& owner, const Property& p, const Object& t, Role role) {
  NestingGuard guard(im, t);
  if (t.tag != "texture" && t.tag != "spectrum") wrong_kind(owner, p, "a colour, spectrum or texture");
  const std::string what = owner.label() + ": parameter " + quote(p.name);
  Color c;
  if (t.type == "bitmap") {
    if (role != Role::reflectance) fail(t.place, what + " takes a constant in pathcl, not a texture");
    c.texture = bitmap_json(im, t, TextureUse::color);
    return c;
  }
  if (t.type == "checkerboard") {
    if (role != Role::reflectance) fail(t.place, what + " takes a constant in pathcl, not a texture");
    c.checker = checkerboard(im, t);
    return c;
  }
  if (t.type == "uniform") {
    if (!find(t, "value")) fail(t.place, t.label() + ": needs a value");
    c.rgb = glm::dvec3(number(t, "value", 0));
  } else if (t.type == "srgb") {
    const Property* color = find(t, "color");
    if (!color) fail(t.place, t.label() + ": needs a color");
    c.rgb = read_color(im, t, *color, Role::unbounded).rgb;
    consume(t, {"unbounded"});
  } else if (t.type == "d65") {  // white in sRGB, times its colour and scale
    const Property* color = find(t, "color");
    c.rgb = (color ? read_color(im, t, *color, Role::unbounded).rgb : glm::dvec3(1)) * number(t, "scale", 1) *
            d65_to_srgb();
  } else if (t.type == "blackbody") {
    if (role != Role::emission) fail(t.place, what + ": a blackbody is an emission spectrum");
    std::optional<double> kelvin = optional_number(t, "temperature");
    if (!kelvin || !(*kelvin > 0)) fail(t.place, t.label() + ": needs a temperature > 0 (kelvin)");
    c.rgb = blackbody_to_srgb(*kelvin);
  } else if (t.type == "regular" || t.type == "irregular") {
    Spectrum s;
    std::vector<double> values = numbers_or_fail(place_of(t, "values"), t.label() + " values", text(t, "values", ""));
    if (t.type == "regular") {
      double lo = number(t, "wavelength_min", 360), hi = number(t, "wavelength_max", 830);
      for (size_t i = 0; i < values.size(); ++i)
        s.wavelengths.push_back(values.size() < 2 ? lo : lo + (hi - lo) * double(i) / double(values.size() - 1));
    } else {
      s.wavelengths =
          numbers_or_fail(place_of(t, "wavelengths"), t.label() + " wavelengths", text(t, "wavelengths", ""));
      if (s.wavelengths.size() != values.size())
        fail(t.place, t.label() + ": " + std::to_string(s.wavelengths.size()) + " wavelengths but " +
                          std::to_string(values.size()) + " values");
    }
    s.values = values;
    check_spectrum(t.place, s);
    c.rgb = spectrum_rgb(im, t.place, s, role);
  } else {
    fail(t.place, t.label() +
                      " is not supported (supported: bitmap and checkerboard textures, and the spectra uniform, srgb, "
                      "d65, blackbody, regular and irregular)");
  }
  warn_unused(im, t);
  return c;
}

Color read_color(Importer& im, const Object& owner, const Property& p, Role role) {
  Color c;
  switch (p.kind) {
    case Kind::number:
    case Kind::integer:
      c.rgb = glm::dvec3(p.number);
      break;
    case Kind::rgb:
      c.rgb = p.vec;
      break;
    case Kind::spectrum:
      c.rgb = spectrum_rgb(im, p.place, p.spectrum, role);
      break;
    case Kind::blackbody:
      if (role != Role::emission)
        fail(p.place, owner.label() + ": parameter " + quote(p.name) + ": a blackbody is an emission spectrum");
      c.rgb = blackbody_to_srgb(p.number) * p.vec.x;
      break;
    case Kind::object:
    case Kind::reference:
      return color_object(im, owner, p, resolve(im, p), role);
    default:
      wrong_kind(owner, p, "a colour (<rgb>, <spectrum>, <float>) or a texture");
  }
  return c;
}

// A reflectance parameter: a texture, or a colour clamped into [0, 1], which pathcl's materials need.
Color reflectance(Importer& im, const Object& o, const std::string& name, double fallback) {
  const Property* p = find(o, name);
  if (!p) return Color{glm::dvec3(fallback), nullptr, std::nullopt};
  Color c = read_color(im, o, *p, Role::reflectance);
  c.each_constant([&](glm::dvec3& rgb) {  // a constant, or a checkerboard's colours
    glm::dvec3 clamped = glm::clamp(rgb, 0.0, 1.0);
    if (clamped != rgb)
      im.warn(p->place, o.label() + ": " + name + " " + format_color(rgb) +
                            " is clamped into [0, 1] (pathcl's materials cannot reflect more than they receive)");
    rgb = clamped;
  });
  return c;
}

// An emitter's colour (radiance, intensity, irradiance), 1 by default as in Mitsuba.
glm::dvec3 emission(Importer& im, const Object& o, const std::string& name) {
  const Property* p = find(o, name);
  if (!p) return glm::dvec3(1);
  return read_color(im, o, *p, Role::emission).rgb;
}

// ---------------------------------------------------------------------------------------------------
// BSDFs as pathcl materials

const char* const kSupportedBsdfs =
    "diffuse, dielectric, thindielectric, roughdielectric (as smooth), conductor, roughconductor, plastic, "
    "roughplastic, phong, "
    "twosided, mask, bumpmap and normalmap (without the map), null";

// Mitsuba's fit of the hemispherical Fresnel reflectance of a dielectric boundary (mitsuba/render/fresnel.h):
// Egan and Hilgeman (1973) for eta < 1, d'Eon and Irving (2011) above.
double fresnel_diffuse_reflectance(double eta) {
  double x = 1 / eta;
  if (eta < 1) return 0.0636 * x + eta * (eta * -1.4399 + 0.7099) + 0.6681;
  return 0.919317 + x * (-3.4793 + x * (6.75335 + x * (-7.80989 + x * (4.98554 + x * -1.36881))));
}

// The reflectance of a conductor of complex index eta + i k at normal incidence.
glm::dvec3 conductor_reflectance_at_normal(glm::dvec3 eta, glm::dvec3 k) {
  glm::dvec3 k2 = k * k;
  return ((eta - 1.0) * (eta - 1.0) + k2) / ((eta + 1.0) * (eta + 1.0) + k2);
}

// An index of refraction: a number, or one of Mitsuba's names ("bk7", "water", ...).
double index_of_refraction(const Object& b, const std::string& name, const std::string& fallback) {
  const Property* p = find(b, name);
  std::string named = fallback;
  if (p && (p->kind == Kind::number || p->kind == Kind::integer)) return p->number;
  if (p && p->kind != Kind::text) wrong_kind(b, *p, "a <float> or a <string> naming a material");
  if (p) named = p->text;
  double ior = 0;
  if (!named_ior(lower(named), &ior))
    fail(p ? p->place : b.place, b.label() + ": unknown index of refraction " + quote(named) +
                                     " (expected a number or one of " + named_ior_list() + ")");
  return ior;
}

// int_ior / ext_ior, which is all that a smooth boundary's Fresnel term and refraction depend on.
double relative_ior(const Object& b, const std::string& interior_default) {
  double eta = index_of_refraction(b, "int_ior", interior_default) / index_of_refraction(b, "ext_ior", "air");
  if (!(eta > 0 && eta <= 10))
    fail(b.place, b.label() + ": int_ior / ext_ior = " + format_number(eta) +
                      ", expected a relative index of refraction in (0, 10]");
  return eta;
}

// A microfacet roughness as pathcl's: roughness = sqrt(alpha), in [0.01, 1]. Beckmann becomes GGX of the
// same alpha; anisotropic alphas their mean.
double roughness(Importer& im, const Object& b, const std::string& default_distribution) {
  std::string distribution = lower(text(b, "distribution", default_distribution));
  if (distribution == "beckmann")
    im.warn(place_of(b, "distribution"), b.label() +
                                             ": the Beckmann microfacet distribution becomes GGX of the same alpha "
                                             "(pathcl's only one): highlights have longer tails");
  else if (distribution != "ggx")
    fail(place_of(b, "distribution"),
         b.label() + ": distribution " + quote(distribution) + " (expected beckmann or ggx)");
  consume(b, {"sample_visible"});
  auto alpha_at = [&](const std::string& name, double fallback) {
    const Property* p = find(b, name);
    if (!p) return fallback;
    if (p->kind != Kind::number && p->kind != Kind::integer)
      fail(p->place, b.label() + ": " + name + " must be a number (pathcl's roughness is constant over a material)");
    return p->number;
  };
  double alpha = alpha_at("alpha", 0.1);
  if (find(b, "alpha_u") || find(b, "alpha_v")) {
    double u = alpha_at("alpha_u", alpha), v = alpha_at("alpha_v", alpha);
    if (u != v)
      im.warn(place_of(b, "alpha_u"), b.label() + ": anisotropic roughness (alpha_u " + format_number(u) +
                                          ", alpha_v " + format_number(v) + ") becomes isotropic alpha " +
                                          format_number((u + v) / 2) + " (their mean)");
    alpha = (u + v) / 2;
  }
  double r = std::sqrt(std::max(alpha, 0.0));
  double clamped = std::clamp(r, 0.01, 1.0);
  if (clamped != r)
    im.warn(place_of(b, "alpha"), b.label() + ": alpha " + format_number(alpha) + " (roughness " + format_number(r) +
                                      ") is clamped to pathcl's range of roughness [0.01, 1]");
  return clamped;
}

// A conductor's complex index of refraction; *perfect when it is Mitsuba's "none" (eta 0, k 1), which
// reflects everything at every angle.
struct ConductorIndex {
  glm::dvec3 eta{0}, k{1};
  bool perfect = true;
};

ConductorIndex conductor_index(Importer& im, const Object& b) {
  ConductorIndex c;
  std::string material = text(b, "material", "none");
  if (find(b, "eta") || material == "none") {
    const Property* eta = find(b, "eta");
    const Property* k = find(b, "k");
    if (eta) c.eta = read_color(im, b, *eta, Role::unbounded).rgb;
    if (k) c.k = read_color(im, b, *k, Role::unbounded).rgb;
  } else if (!named_conductor(material, &c.eta, &c.k)) {
    fail(place_of(b, "material"),
         b.label() + ": unknown conductor " + quote(material) + " (expected one of " + named_conductor_list() + ")");
  }
  c.perfect = c.eta == glm::dvec3(0) && c.k == glm::dvec3(1);
  return c;
}

// What one bsdf (with the wrappers around it) becomes.
struct BsdfBuild {
  json material;
  bool two_sided = false;
  bool transmissive = false;  // lets light through: not one-sided in Mitsuba either
  bool dielectric = false;    // its front and back differ in pathcl too
};

void build_bsdf(Importer& im, const Object& b, BsdfBuild& out);

const Object& nested_bsdf(const Importer& im, const Object& b) {
  std::vector<const Object*> inner = nested(im, b, "bsdf");
  if (inner.empty()) fail(b.place, b.label() + ": expected a nested <bsdf>");
  if (inner.size() > 1 && b.type != "twosided")
    fail(inner[1]->place, b.label() + ": expected one nested <bsdf>, got " + std::to_string(inner.size()));
  return *inner[0];
}

void build_twosided(Importer& im, const Object& b, BsdfBuild& out) {
  std::vector<const Object*> inner = nested(im, b, "bsdf");
  if (inner.empty() || inner.size() > 2) fail(b.place, b.label() + ": expected one or two nested <bsdf>s");
  if (inner.size() == 2 && inner[0] != inner[1])
    im.warn(inner[1]->place, b.label() + ": the back side's " + inner[1]->label() +
                                 " is not supported; both sides are " + inner[0]->label());
  consume(b, {"allow_transmission"});
  out.two_sided = true;
  build_bsdf(im, *inner[0], out);
}

// Mitsuba's mask: opacity (0.5 by default) over a nested bsdf, as pathcl's cut-out opacity.
void build_mask(Importer& im, const Object& b, BsdfBuild& out) {
  build_bsdf(im, nested_bsdf(im, b), out);
  const Property* p = find(b, "opacity");
  if (p && is_object(*p) && resolve(im, *p).type == "bitmap") {
    const Object& t = resolve(im, *p);
    im.warn(t.place, b.label() +
                         ": pathcl reads an opacity map's alpha channel (its red channel where alpha is opaque); "
                         "Mitsuba its luminance");
    out.material["opacity"] = bitmap_json(im, t, TextureUse::opacity);
    return;
  }
  if (p && is_object(*p) && resolve(im, *p).type == "checkerboard") {
    // Mitsuba reads an opacity by the texture's eval_1, which its checkerboard (3.9) answers with the colours
    // the other way round (color0 where the axes differ: src/textures/checkerboard.cpp), each colour by its
    // mean, clipped to [0, 1]. pathcl reads the red channel: grey colours, swapped.
    Checker c = checkerboard(im, resolve(im, *p));
    auto opacity = [](glm::dvec3 v) { return glm::dvec3(std::clamp((v.x + v.y + v.z) / 3, 0.0, 1.0)); };
    std::tie(c.color0, c.color1) = std::make_pair(opacity(c.color1), opacity(c.color0));
    out.material["opacity"] = c.to_json();
    return;
  }
  glm::dvec3 c = p ? read_color(im, b, *p, Role::reflectance).rgb : glm::dvec3(0.5);
  out.material["opacity"] = std::clamp((c.x + c.y + c.z) / 3, 0.0, 1.0);  // Mitsuba reads a colour's mean
}

void build_bump(Importer& im, const Object& b, BsdfBuild& out) {
  im.warn(b.place,
          b.label() + ": the " + b.type +
              " is ignored (pathcl has no bump or normal maps): the nested bsdf shades with the mesh's normals");
  nested(im, b, "texture");
  consume(b, {"scale", "normalmap", "flip_invalid_normals", "use_shadowing_function"});
  build_bsdf(im, nested_bsdf(im, b), out);
}

void build_dielectric(Importer& im, const Object& b, BsdfBuild& out) {
  out.material = {{"type", "dielectric"}, {"ior", relative_ior(b, "bk7")}};
  if (find(b, "specular_transmittance"))
    out.material["transmittance"] = reflectance(im, b, "specular_transmittance", 1).to_json();
  Color specular = reflectance(im, b, "specular_reflectance", 1);
  if (specular.textured() || specular.rgb != glm::dvec3(1))
    im.warn(
        place_of(b, "specular_reflectance"),
        b.label() +
            ": specular_reflectance is not supported (pathcl's dielectric reflects the Fresnel term alone); ignored");
  out.transmissive = true;
  out.dielectric = b.type != "thindielectric";  // a thin sheet is the same from both sides
  if (b.type == "roughdielectric") {
    consume(b, {"alpha", "alpha_u", "alpha_v", "distribution", "sample_visible"});
    im.warn(b.place,
            b.label() + ": rendered as smooth glass (pathcl's dielectric is smooth; its roughness is dropped)");
  }
}

// Mitsuba's smooth conductor as pathcl's mirror with eta and k: specular_reflectance times the conductor
// Fresnel term at the incident angle, as Mitsuba's. Its default, "none" (eta 0, k 1), reflects everything
// at every angle: a plain mirror.
void build_conductor(Importer& im, const Object& b, BsdfBuild& out) {
  ConductorIndex index = conductor_index(im, b);
  out.material = {{"type", "mirror"}, {"reflectance", reflectance(im, b, "specular_reflectance", 1).to_json()}};
  if (!index.perfect) {
    if (glm::any(glm::lessThan(index.eta, glm::dvec3(0))) || glm::any(glm::lessThan(index.k, glm::dvec3(0))))
      fail(b.place, b.label() + ": eta " + format_color(index.eta) + " and k " + format_color(index.k) +
                        ": expected values >= 0");
    out.material["eta"] = vec_json(index.eta);
    out.material["k"] = vec_json(index.k);
  }
}

void build_rough_conductor(Importer& im, const Object& b, BsdfBuild& out) {
  out.material = {{"type", "rough_conductor"}, {"roughness", roughness(im, b, "beckmann")}};
  // Mitsuba 3's microfacet masking-shadowing is the separable G1(wi) G1(wo) (mitsuba/render/microfacet.h),
  // pathcl's (and pbrt-v4's) the height-correlated 1 / (1 + Lambda(wi) + Lambda(wo)): at least as large,
  // equal where either direction is normal, larger towards grazing angles.
  im.warn(b.place, b.label() +
                       ": pathcl's masking-shadowing is the height-correlated Smith term where Mitsuba's is separable: "
                       "the same at normal incidence, slightly brighter towards grazing angles");
  ConductorIndex index = conductor_index(im, b);
  Color specular = reflectance(im, b, "specular_reflectance", 1);
  if (specular.textured()) {
    im.warn(place_of(b, "specular_reflectance"),
            b.label() + ": a specular_reflectance texture is not supported on pathcl's rough_conductor; taken as 1");
    specular.rgb = glm::dvec3(1);
  }
  glm::dvec3 f0 = conductor_reflectance_at_normal(index.eta, index.k);
  bool positive_eta = index.eta.x > 0 && index.eta.y > 0 && index.eta.z > 0;
  if (index.perfect) {
    out.material["specular"] = vec_json(specular.rgb);  // pathcl: eta 1, k from it, within 1e-4 of a perfect conductor
  } else if (specular.rgb != glm::dvec3(1) || !positive_eta) {
    glm::dvec3 r = glm::clamp(specular.rgb * f0, 0.0, 1.0);
    out.material["specular"] = vec_json(r);
    im.warn(b.place, b.label() + ": the Fresnel term becomes that of a conductor reflecting " + format_color(r) +
                         " at normal incidence (specular_reflectance times the conductor's; pathcl's rough_conductor "
                         "takes eta > 0 and no tint)");
  } else {
    out.material["eta"] = vec_json(index.eta);
    out.material["k"] = vec_json(index.k);
  }
}

// Mitsuba's smooth plastic (src/bsdfs/plastic.cpp) reflects, besides the coat's Fresnel mirror,
//   diffuse / (eta^2 (1 - F_dr)) (1 - F(cos_i)) (1 - F(cos_o)) cos_o / pi,
// F_dr the diffuse Fresnel reflectance inside the coat (times diffuse where `nonlinear`): light reflected
// back into the base, summed. pathcl's plastic is diffuse (1 - F(cos_i)) (1 - F(cos_o)) / pi, so the two
// agree exactly when pathcl's diffuse is Mitsuba's divided by eta^2 (1 - F_dr).
void build_plastic(Importer& im, const Object& b, BsdfBuild& out) {
  double eta = relative_ior(b, "polypropylene");
  bool nonlinear = boolean(b, "nonlinear", false);
  Color diffuse = reflectance(im, b, "diffuse_reflectance", 0.5);
  double fdr = fresnel_diffuse_reflectance(1 / eta);
  if (!diffuse.texture.is_null()) {
    im.warn(place_of(b, "diffuse_reflectance"),
            b.label() +
                ": the diffuse texture is used unscaled: Mitsuba's plastic scales it by 1 / (eta^2 (1 - F_dr)) = " +
                format_number(1 / (eta * eta * (1 - fdr))) + (nonlinear ? " (nonlinear: per texel)" : "") +
                ", and pathcl's textures take no factor");
  }
  diffuse.each_constant([&](glm::dvec3& c) {  // a constant, or a checkerboard's colours: scaled exactly
    glm::dvec3 scaled = c / (eta * eta * (1.0 - (nonlinear ? c * fdr : glm::dvec3(fdr))));
    glm::dvec3 clamped = glm::min(scaled, glm::dvec3(1));
    if (clamped != scaled)
      im.warn(b.place,
              b.label() + ": Mitsuba's diffuse lobe, " + format_color(scaled) +
                  " (diffuse_reflectance / (eta^2 (1 - F_dr))), exceeds 1 and is clamped to 1 for pathcl's plastic");
    c = clamped;
  });
  Color specular = reflectance(im, b, "specular_reflectance", 1);
  if (specular.textured() || specular.rgb != glm::dvec3(1))
    im.warn(
        place_of(b, "specular_reflectance"),
        b.label() +
            ": specular_reflectance is not supported (pathcl's plastic coat reflects the Fresnel term alone); ignored");
  out.material = {{"type", "plastic"}, {"diffuse", diffuse.to_json()}, {"ior", eta}};
  if (b.type == "roughplastic") {
    out.material["roughness"] = roughness(im, b, "beckmann");
    im.warn(b.place, b.label() +
                         ": Mitsuba's rough plastic transmits into its base by tabulated rough-coat terms; pathcl's by "
                         "the smooth coat's (1 - F): the diffuse part is approximated by the smooth plastic's");
  }
}

// Mitsuba 0.6's phong: the normalised modified Phong model that pathcl's phong is.
void build_phong(Importer& im, const Object& b, BsdfBuild& out) {
  double exponent = number(b, "exponent", 30);
  Color diffuse = reflectance(im, b, "diffuse_reflectance", 0.5);
  Color specular = reflectance(im, b, "specular_reflectance", 0.2);
  if (specular.textured())
    fail(place_of(b, "specular_reflectance"),
         b.label() + ": a specular_reflectance texture is not supported (pathcl's phong takes a constant specular)");
  if (diffuse.texture.is_null()) {  // a constant, or a checkerboard's colours
    double sum = 0;
    diffuse.each_constant([&](glm::dvec3& c) {
      sum = std::max({sum, c.x + specular.rgb.x, c.y + specular.rgb.y, c.z + specular.rgb.z});
    });
    if (sum > 1) {
      im.warn(b.place, b.label() + ": diffuse + specular reflectance reaches " + format_number(sum) +
                           "; both are scaled by 1/" + format_number(sum) +
                           " so that energy is conserved (pathcl requires it)");
      diffuse.each_constant([&](glm::dvec3& c) { c /= sum; });
      specular.rgb /= sum;
    }
  }
  out.material = {
      {"type", "phong"}, {"diffuse", diffuse.to_json()}, {"specular", vec_json(specular.rgb)}, {"exponent", exponent}};
}

void build_bsdf(Importer& im, const Object& b, BsdfBuild& out) {
  NestingGuard guard(im, b);
  const std::string& t = b.type;
  if (t == "twosided") {
    build_twosided(im, b, out);
  } else if (t == "mask") {
    build_mask(im, b, out);
  } else if (t == "bumpmap" || t == "normalmap") {
    build_bump(im, b, out);
  } else if (t == "diffuse") {
    out.material = {{"type", "diffuse"}, {"reflectance", reflectance(im, b, "reflectance", 0.5).to_json()}};
  } else if (t == "dielectric" || t == "roughdielectric") {
    build_dielectric(im, b, out);
  } else if (t == "thindielectric") {
    build_dielectric(im, b, out);
    out.material["type"] = "thin_dielectric";
  } else if (t == "conductor") {
    build_conductor(im, b, out);
  } else if (t == "roughconductor") {
    build_rough_conductor(im, b, out);
  } else if (t == "plastic" || t == "roughplastic") {
    build_plastic(im, b, out);
  } else if (t == "phong") {
    build_phong(im, b, out);
  } else if (t == "null") {  // invisible: every ray passes
    out.material = {{"type", "diffuse"}, {"reflectance", vec_json(glm::dvec3(0))}, {"opacity", 0}};
    out.two_sided = true;
  } else {
    fail(b.place, "bsdf " + quote(t) + " is not supported (supported: " + kSupportedBsdfs + ")");
  }
  warn_unused(im, b);
}

bool has_texture(const json& material) {
  for (const auto& [key, value] : material.items())
    if (value.is_object() && (value.contains("texture") || value.contains("checkerboard"))) return true;
  return false;
}

std::string unique_name(Importer& im, const std::string& wanted, bool is_id) {
  if (is_id) return wanted;  // ids are unique, and taken from the start
  std::string name = wanted;
  for (int i = 2; im.names.count(name); ++i) name = wanted + "-" + std::to_string(i);
  im.names.insert(name);
  return name;
}

MaterialInfo add_material(Importer& im, const std::string& name, const BsdfBuild& build, const Object& origin) {
  MaterialInfo info;
  info.name = name;
  info.dielectric = build.dielectric;
  info.one_sided = !build.two_sided && !build.transmissive;
  info.textured = has_texture(build.material);
  im.materials[name] = build.material;
  im.origin("materials." + name, origin);
  return info;
}

// The pathcl material of a bsdf (once per bsdf): named by its id, else "bsdf@LINE".
const MaterialInfo& material_for(Importer& im, const Object& b) {
  auto it = im.material_of.find(b.index);
  if (it != im.material_of.end()) return it->second;
  BsdfBuild build;
  build_bsdf(im, b, build);
  std::string name = unique_name(im, b.id.empty() ? "bsdf@" + std::to_string(b.place.line) : b.id, !b.id.empty());
  // A black diffuse bsdf (an emitter's) is black from behind in both.
  const bool black = build.material.value("type", "") == "diffuse" && build.material.contains("reflectance") &&
                     build.material["reflectance"] == json::array({0.0, 0.0, 0.0});
  if (!build.two_sided && !build.transmissive && !black)
    im.warn(b.place,
            b.label() +
                " is one-sided in Mitsuba (black seen from behind; a twosided bsdf around it reflects on both sides), "
                "pathcl's material reflects on both sides");
  return im.material_of[b.index] = add_material(im, name, build, b);
}

// Mitsuba's default bsdf of a shape without one: diffuse 0.5, one-sided; black on an emitter.
const MaterialInfo& default_material(Importer& im, bool emitter, const Object& shape) {
  const std::string key = emitter ? "default-emitter" : "default";
  auto it = im.default_material.find(key);
  if (it != im.default_material.end()) return it->second;
  BsdfBuild build;
  build.material = {{"type", "diffuse"}, {"reflectance", vec_json(glm::dvec3(emitter ? 0 : 0.5))}};
  build.two_sided = emitter;  // black on both sides either way
  if (!emitter)
    im.warn(shape.place,
            shape.label() +
                " has no bsdf: Mitsuba's default, a one-sided diffuse of reflectance 0.5, becomes the material " +
                quote(key) + ", which reflects on both sides");
  return im.default_material[key] = add_material(im, unique_name(im, key, false), build, shape);
}

// ---------------------------------------------------------------------------------------------------
// Shapes

// An inline triangle mesh (pathcl's "triangles") for Mitsuba's rectangle, cube, disk and cylinder, faces
// counter-clockwise seen from the side Mitsuba's normals point to.
struct Triangles {
  std::vector<glm::dvec3> positions;
  std::vector<glm::dvec2> uvs;  // Mitsuba's (v = 0 at an image's top row)
  std::vector<glm::ivec3> faces;
  double ring_scale = 1;  // a tessellated round shape: its ring's radius over the round one's
};

// [-1, 1]^2 in z = 0, normal +z, uv = ((x + 1) / 2, (y + 1) / 2) (src/shapes/rectangle.cpp).
Triangles rectangle_mesh() {
  Triangles t;
  t.positions = {{-1, -1, 0}, {1, -1, 0}, {-1, 1, 0}, {1, 1, 0}};
  t.uvs = {{0, 0}, {1, 0}, {0, 1}, {1, 1}};
  t.faces = {{1, 2, 0}, {1, 3, 2}};
  return t;
}

// [-1, 1]^3 with outward normals (src/shapes/cube.cpp): four vertices a face, at the corners listed (corner
// c at (+-1, +-1, +-1), bit k of c the sign of axis k), with uvs (0, 1), (1, 1), (1, 0), (0, 0) in that order.
Triangles cube_mesh() {
  static const int corners[6][4] = {{1, 5, 4, 0}, {3, 2, 6, 7}, {1, 3, 7, 5}, {5, 7, 6, 4}, {4, 6, 2, 0}, {3, 1, 0, 2}};
  static const glm::dvec2 uvs[4] = {{0, 1}, {1, 1}, {1, 0}, {0, 0}};
  Triangles t;
  for (const auto& face : corners) {
    const int base = int(t.positions.size());
    for (int k = 0; k < 4; ++k) {
      int c = face[k];
      t.positions.push_back({c & 1 ? 1 : -1, c & 2 ? 1 : -1, c & 4 ? 1 : -1});
      t.uvs.push_back(uvs[k]);
    }
    t.faces.push_back({base, base + 1, base + 2});
    t.faces.push_back({base + 3, base, base + 2});
  }
  return t;
}

constexpr int kDiskSegments = 256;
constexpr int kCylinderSegments = 128;

// Vertex i of a ring of n segments around the z axis at height z, counter-clockwise seen from +z, from the
// +x axis on: n + 1 vertices, the last (the seam, where Mitsuba's angle reaches 2 pi) at the first's position.
glm::dvec3 ring_vertex(int i, int n, double radius, double z) {
  const double angle = i == n ? 0 : i * (2 * M_PI / n);
  return {radius * std::cos(angle), radius * std::sin(angle), z};
}

// The unit disk in z = 0, normal +z, uv = (radius, angle / 2 pi) (src/shapes/disk.cpp), as a fan of
// kDiskSegments triangles whose ring is scaled to give the fan the disk's area. Each triangle has a centre
// vertex of its own, at the middle of its angle, since the angle is undefined there.
Triangles disk_mesh() {
  const int n = kDiskSegments;
  Triangles t;
  t.ring_scale = std::sqrt(2 * M_PI / (n * std::sin(2 * M_PI / n)));  // n sin(2 pi / n) r^2 / 2 = pi
  for (int i = 0; i <= n; ++i) {
    t.positions.push_back(ring_vertex(i, n, t.ring_scale, 0));
    t.uvs.push_back({1, double(i) / n});
  }
  for (int i = 0; i < n; ++i) {
    t.positions.push_back({0, 0, 0});
    t.uvs.push_back({0, (i + 0.5) / n});
    t.faces.push_back({n + 1 + i, i, i + 1});
  }
  return t;
}

// Mitsuba's cylinder (src/shapes/cylinder.cpp): the open tube (no caps) of radius 1 around the z axis from
// z = 0 to 1, normals outward, uv = (angle / 2 pi, z), as kCylinderSegments quads (two triangles each) between
// two rings whose radius is scaled to give the tube the cylinder's area (a perimeter of 2 pi). Mitsuba's
// radius, p0 and p1 place it: translate(p0) to_frame(p1 - p0) scale(radius, radius, |p1 - p0|), the frame's
// first two axes Mitsuba's coordinate_system of the direction (basis_first_vector).
Triangles cylinder_mesh(double radius, glm::dvec3 p0, glm::dvec3 p1) {
  const int n = kCylinderSegments;
  const double length = glm::length(p1 - p0);
  const glm::dvec3 axis = (p1 - p0) / length, first = basis_first_vector(axis), second = glm::cross(axis, first);
  Triangles t;
  t.ring_scale = M_PI / (n * std::sin(M_PI / n));  // n 2 r sin(pi / n) = 2 pi
  for (int z = 0; z < 2; ++z)
    for (int i = 0; i <= n; ++i) {
      const glm::dvec3 local = ring_vertex(i, n, t.ring_scale, z);
      t.positions.push_back(p0 + radius * (local.x * first + local.y * second) + length * local.z * axis);
      t.uvs.push_back({double(i) / n, double(z)});
    }
  for (int i = 0; i < n; ++i) {  // counter-clockwise seen from outside: along the angle, then up
    const int bottom = i, top = n + 1 + i;
    t.faces.push_back({bottom, bottom + 1, top + 1});
    t.faces.push_back({bottom, top + 1, top});
  }
  return t;
}

// pathcl's "triangles" keys; v flipped, since pathcl's v = 0 is an image's bottom row.
json triangles_json(const Triangles& t, bool flip) {
  json positions = json::array(), uvs = json::array(), indices = json::array();
  for (glm::dvec3 p : t.positions) positions.push_back(vec_json(p));
  for (glm::dvec2 uv : t.uvs) uvs.push_back(json::array({uv.x, 1 - uv.y}));
  for (glm::ivec3 f : t.faces) {
    glm::uvec3 u(f);  // unsigned, as a parsed JSON file holds them
    indices.push_back(flip ? json::array({u.x, u.z, u.y}) : json::array({u.x, u.y, u.z}));
  }
  return {{"type", "triangles"}, {"positions", positions}, {"indices", indices}, {"uvs", uvs}};
}

// The radiance of the area emitter nested in a shape.
glm::dvec3 area_radiance(Importer& im, const Object& e) {
  if (e.type != "area") fail(e.place, e.label() + " cannot be attached to a shape (expected an area emitter)");
  if (find(e, "to_world"))
    fail(place_of(e, "to_world"), e.label() + ": an area emitter takes no to_world (its shape places it)");
  const Property* p = find(e, "radiance");
  glm::dvec3 radiance(1);
  if (p) {
    Color c = read_color(im, e, *p, Role::emission);
    if (c.textured())
      fail(p->place, e.label() + ": a textured radiance is not supported (pathcl's emitters have one colour)");
    radiance = c.rgb;
  }
  consume(e, {"sampling_weight"});
  warn_unused(im, e);
  return radiance;
}

// A mesh file (obj, ply) as pathcl's "mesh".
json mesh_json(Importer& im, const Object& s, const MaterialInfo& material, bool emitter) {
  std::optional<std::string> filename = optional_text(s, "filename");
  if (!filename) fail(s.place, s.label() + ": needs a filename");
  // Mitsuba ignores a mesh's vertex colours unless a texture asks for them; pathcl would multiply by them.
  json j = {{"type", "mesh"}, {"file", scene_file_path(im, *filename)}, {"vertex_colors", false}};
  // Mitsuba smooths a mesh without normals across all its edges, weighting the faces by their angle at
  // the vertex: pathcl's smoothing at 180 degrees. File normals are used by both.
  if (!boolean(s, "face_normals", false)) {
    j["smooth"] = true;
    j["smooth_angle_degrees"] = 180;
  }
  if (std::optional<double> angle = optional_number(s, "max_smooth_angle")) {  // 0.6
    j["smooth"] = true;
    j["smooth_angle_degrees"] = std::clamp(*angle, 0.0, 180.0);
  }
  if (s.type != "serialized" && !boolean(s, "flip_tex_coords", s.type == "obj") && material.textured)
    im.warn(place_of(s, "flip_tex_coords"),
            s.label() +
                ": Mitsuba reads this mesh's texture coordinates with v = 0 at the image's top row "
                "(flip_tex_coords false), pathcl at its bottom row: the texture appears flipped vertically");
  if (boolean(s, "flip_normals", false)) {
    const Place at = place_of(s, "flip_normals");
    if (emitter)
      fail(at,
           s.label() +
               ": flip_normals on an emitting mesh file is not supported: pathcl emits from the side its faces wind "
               "counter-clockwise (reverse the faces in the file instead)");
    if (material.dielectric)
      fail(at, s.label() +
                   ": flip_normals on a dielectric mesh file is not supported: it swaps the glass's inside and outside "
                   "(reverse the faces in the file instead)");
    if (material.one_sided)
      im.warn(at, s.label() + ": flip_normals is dropped: pathcl's material reflects on both sides of the mesh");
  }
  return j;
}

void convert_shape(Importer& im, const Object& s, const glm::dmat4& placement);

// An instance places the shapes of its shapegroup, each with its own transform after the instance's.
void convert_instance(Importer& im, const Object& inst, const glm::dmat4& placement) {
  std::vector<const Object*> groups = nested(im, inst, "shape");
  if (groups.size() != 1 || groups[0]->type != "shapegroup")
    fail(inst.place, inst.label() + ": expected one shapegroup, nested or as a <ref>");
  const glm::dmat4 m = placement * transform(inst, "to_world");
  for (const Object* shape : nested(im, *groups[0], "shape")) {
    if (shape->type == "shapegroup" || shape->type == "instance")
      fail(shape->place, groups[0]->label() + ": a shapegroup cannot hold a " + shape->type);
    convert_shape(im, *shape, m);
  }
  warn_unused(im, *groups[0]);
  warn_unused(im, inst);
}

void convert_shape(Importer& im, const Object& s, const glm::dmat4& placement) {
  const std::string& type = s.type;
  if (type == "shapegroup") return;  // placed by its instances
  if (type == "instance") return convert_instance(im, s, placement);
  if (type != "obj" && type != "ply" && type != "serialized" && type != "rectangle" && type != "cube" &&
      type != "disk" && type != "cylinder" && type != "sphere")
    fail(s.place, "shape " + quote(type) +
                      " is not supported (supported: obj, ply, serialized, rectangle, cube, disk, cylinder, sphere, "
                      "shapegroup, instance)");
  for (const Object* medium : nested(im, s, "medium"))
    fail(medium->place, s.label() + ": media are not supported (pathcl renders surfaces in a vacuum)");
  for (const Object* sensor : nested(im, s, "sensor"))
    fail(sensor->place, s.label() + ": a sensor attached to a shape is not supported");

  std::vector<const Object*> emitters = nested(im, s, "emitter");
  if (emitters.size() > 1) fail(emitters[1]->place, s.label() + ": expected at most one emitter");
  std::optional<glm::dvec3> radiance;
  if (!emitters.empty()) {
    radiance = area_radiance(im, *emitters[0]);
    im.attached_emitters.insert(emitters[0]->index);
  }
  std::vector<const Object*> bsdfs = nested(im, s, "bsdf");
  if (bsdfs.size() > 1) fail(bsdfs[1]->place, s.label() + ": expected at most one bsdf");
  const MaterialInfo material =
      bsdfs.empty() ? default_material(im, radiance.has_value(), s) : material_for(im, *bsdfs[0]);

  const glm::dmat4 to_world = placement * transform(s, "to_world");
  json j;
  if (type == "obj" || type == "ply" || type == "serialized") {
    j = mesh_json(im, s, material, radiance.has_value());
    // A .serialized file holds several shapes; pathcl's loader flips its v as Mitsuba's reads it.
    if (type == "serialized") {
      const long long index = integer(s, "shape_index", 0);
      if (index < 0 || index > 0xffffffffLL) fail(place_of(s, "shape_index"), s.label() + ": expected a shape_index >= 0");
      j["shape_index"] = static_cast<uint64_t>(index);
    }
  } else if (type == "sphere") {
    j = {{"type", "sphere"},
         {"center", vec_json(optional_vector(s, "center").value_or(glm::dvec3(0)))},
         {"radius", number(s, "radius", 1)}};
    if (boolean(s, "flip_normals", false)) j["flip_normals"] = true;
    if (material.textured)
      im.warn(s.place, s.label() +
                           ": pathcl's sphere has texture coordinates of its own (+y at v = 1), not Mitsuba's (+z at v "
                           "= 0): the texture is placed differently");
  } else if (type == "cylinder") {
    const double radius = number(s, "radius", 1);
    const glm::dvec3 p0 = optional_vector(s, "p0").value_or(glm::dvec3(0)),
                     p1 = optional_vector(s, "p1").value_or(glm::dvec3(0, 0, 1));
    // A negative radius is the same tube turned by 180 degrees about its axis, as in Mitsuba.
    if (!(radius != 0 && std::isfinite(radius)))
      fail(place_of(s, "radius"), s.label() + ": expected a radius other than 0");
    if (!(glm::length(p1 - p0) > 0)) fail(s.place, s.label() + ": p0 and p1 coincide (a cylinder of length 0)");
    const Triangles t = cylinder_mesh(radius, p0, p1);
    j = triangles_json(t, boolean(s, "flip_normals", false));
    // Smooth shading makes the facets a round tube: adjacent ones differ by 360 / 128 = 2.8 degrees.
    j["smooth"] = true;
    j["smooth_angle_degrees"] = 30;
    im.warn(s.place, s.label() + ": tessellated into " + std::to_string(2 * kCylinderSegments) + " triangles (" +
                         std::to_string(kCylinderSegments) +
                         " segments, shaded smooth), their rings' radius scaled by " + format_number(t.ring_scale, 6) +
                         " so that the area is the cylinder's");
  } else {
    const Triangles t = type == "rectangle" ? rectangle_mesh() : type == "cube" ? cube_mesh() : disk_mesh();
    j = triangles_json(t, boolean(s, "flip_normals", false));
    if (type == "disk")
      im.warn(s.place, s.label() + ": tessellated into " + std::to_string(kDiskSegments) +
                           " triangles, their ring's radius scaled by " + format_number(t.ring_scale, 6) +
                           " so that the area is the disk's");
  }
  j["material"] = material.name;
  if (radiance && *radiance != glm::dvec3(0)) j["emission"] = vec_json(*radiance);
  if (!is_identity(to_world)) j["transform"] = {{"matrix", matrix_json(to_world)}};
  const std::string path = "shapes[" + std::to_string(im.shapes.size()) + "]";
  im.origin(path, s);
  if (!emitters.empty()) im.origin(path + ".emission", *emitters[0]);
  im.shapes.push_back(std::move(j));
  consume(s, {"silhouette_sampling_weight"});
  warn_unused(im, s);
}

// ---------------------------------------------------------------------------------------------------
// Emitters

const char* const kSupportedEmitters = "area (in a shape), point, spot, directional, constant, envmap";

// A rotation that places an environment map. Mitsuba looks a world direction w up at d = to_world^-1 w,
// u = atan2(d.x, -d.z) / 2 pi, v = acos(d.y) / pi; pathcl at e = T^-1 w, u = atan2(e.z, e.x) / 2 pi,
// v = acos(e.y) / pi. They agree where e = P d = (-d.z, d.y, d.x), so T = to_world P^-1.
glm::dmat3 environment_rotation(const glm::dmat3& to_world) {
  glm::dmat3 p_inverse(0.0);  // P^-1 = P^T, which takes (-d.z, d.y, d.x) back to d; glm's columns
  p_inverse[0] = {0, 0, -1};
  p_inverse[1] = {0, 1, 0};
  p_inverse[2] = {1, 0, 0};
  return to_world * p_inverse;
}

json environment_map_json(Importer& im, const Object& e) {
  std::optional<std::string> filename = optional_text(e, "filename");
  if (!filename) fail(e.place, e.label() + ": needs a filename (pathcl reads environment maps from image files)");
  const glm::dmat3 to_world(transform(e, "to_world"));
  if (!is_orthonormal(to_world) || glm::determinant(to_world) < 0)
    fail(place_of(e, "to_world"), e.label() +
                                      ": to_world must be a rotation (pathcl places an environment map by a rotation; "
                                      "a scale, shear or mirror has no meaning for directions)");
  json j = {{"type", "environment"}, {"file", scene_file_path(im, *filename)}, {"scale", number(e, "scale", 1)}};
  glm::dmat4 t(environment_rotation(to_world));
  if (!is_identity(t, 1e-12)) j["transform"] = {{"matrix", matrix_json(t)}};
  im.warn(e.place,
          e.label() +
              ": the map's rows lie up to half a texel from Mitsuba's (Mitsuba 3 centres its first and last rows "
              "on the poles, pathcl half a texel from them)");
  consume(e, {"mis_compensation", "cache"});
  return j;
}

void convert_emitter(Importer& im, const Object& e) {
  const std::string& t = e.type;
  json j;
  consume(e, {"sampling_weight"});
  if (t == "area") {
    fail(e.place, e.label() + " must be nested in a <shape> (its surface emits)");
  } else if (t == "point") {
    std::optional<glm::dvec3> position = optional_vector(e, "position");
    if (position && find(e, "to_world")) fail(e.place, e.label() + ": give either position or to_world");
    j = {{"type", "point"},
         {"position", vec_json(position.value_or(transform_point(transform(e, "to_world"), glm::dvec3(0))))},
         {"intensity", vec_json(emission(im, e, "intensity"))}};
  } else if (t == "spot") {
    const glm::dmat4 m = transform(e, "to_world");
    const double cutoff = number(e, "cutoff_angle", 20);
    const double beam = number(e, "beam_width", cutoff * 3 / 4);
    if (!(cutoff > 0 && cutoff <= 180))
      fail(place_of(e, "cutoff_angle"), e.label() + ": cutoff_angle must be in (0, 180] degrees");
    if (find(e, "texture")) fail(place_of(e, "texture"), e.label() + ": a projected texture is not supported");
    j = {{"type", "spot"},
         {"position", vec_json(transform_point(m, glm::dvec3(0)))},
         {"direction", vec_json(transform_vector(m, {0, 0, 1}))},
         {"intensity", vec_json(emission(im, e, "intensity"))},
         {"outer_angle_degrees", cutoff},
         {"inner_angle_degrees", std::clamp(beam, 0.0, cutoff)}};
    if (beam < cutoff)
      im.warn(e.place, e.label() +
                           ": between beam_width and cutoff_angle Mitsuba's intensity falls linearly in the angle, "
                           "pathcl's as a smoothstep in its cosine");
  } else if (t == "directional") {
    std::optional<glm::dvec3> direction = optional_vector(e, "direction");
    if (direction && find(e, "to_world")) fail(e.place, e.label() + ": give either direction or to_world");
    j = {{"type", "directional"},
         {"direction", vec_json(direction.value_or(transform_vector(transform(e, "to_world"), {0, 0, 1})))},
         {"irradiance", vec_json(emission(im, e, "irradiance"))}};
  } else if (t == "constant" || t == "envmap") {
    if (im.environment)
      fail(e.place, e.label() + ": a second environment emitter (pathcl renders at most one: constant or envmap)");
    im.environment = true;
    j = t == "constant" ? json{{"type", "environment"}, {"radiance", vec_json(emission(im, e, "radiance"))}}
                        : environment_map_json(im, e);
  } else {
    fail(e.place, "emitter " + quote(t) + " is not supported (supported: " + kSupportedEmitters + ")");
  }
  im.origin("lights[" + std::to_string(im.lights.size()) + "]", e);
  im.lights.push_back(std::move(j));
  warn_unused(im, e);
}

// ---------------------------------------------------------------------------------------------------
// Sensor, film, sampler and integrator

struct Film {
  int width = 768, height = 576;  // Mitsuba's defaults
  json filter = {{"type", "gaussian"}, {"sigma", 0.5}, {"radius", 2.0}};
  const Object* film = nullptr;
  const Object* rfilter = nullptr;
};

json filter_json(Importer& im, const Object& f) {
  json j;
  if (f.type == "box") {
    j = {{"type", "box"}};
  } else if (f.type == "tent") {
    j = {{"type", "tent"}, {"radius", number(f, "radius", 1)}};
  } else if (f.type == "gaussian") {  // cut off at 4 standard deviations, as Mitsuba's
    double sigma = number(f, "stddev", 0.5);
    j = {{"type", "gaussian"}, {"sigma", sigma}, {"radius", 4 * sigma}};
  } else if (f.type == "mitchell" || f.type == "catmullrom" || f.type == "lanczos") {
    consume(f, {"b", "c", "lobes"});
    im.warn(f.place, f.label() + " becomes a box filter (pathcl has box, tent and gaussian): edges are less smoothed");
    j = {{"type", "box"}};
  } else {
    fail(f.place, "rfilter " + quote(f.type) +
                      " is not supported (supported: box, tent, gaussian; mitchell, catmullrom and lanczos as box)");
  }
  warn_unused(im, f);
  return j;
}

Film read_film(Importer& im, const Object* f) {
  Film film;
  film.film = f;
  if (!f) return film;
  if (f->type != "hdrfilm" && f->type != "ldrfilm" && f->type != "tiledhdrfilm")
    fail(f->place, "film " + quote(f->type) + " is not supported (supported: hdrfilm, ldrfilm)");
  for (const char* side : {"width", "height"}) {
    long long v = integer(*f, side, side[0] == 'w' ? 768 : 576);
    if (v < 1 || v > 16384)
      fail(place_of(*f, side), f->label() + ": " + side + " " + std::to_string(v) + ", expected 1 to 16384 pixels");
    (side[0] == 'w' ? film.width : film.height) = int(v);
  }
  bool cropped = integer(*f, "crop_offset_x", 0) != 0 || integer(*f, "crop_offset_y", 0) != 0 ||
                 integer(*f, "crop_width", film.width) != film.width ||
                 integer(*f, "crop_height", film.height) != film.height;
  if (cropped)
    fail(f->place,
         f->label() + ": crop windows are not supported (pathcl renders the whole film; crop the image afterwards)");
  std::vector<const Object*> filters = nested(im, *f, "rfilter");
  if (!filters.empty()) {
    film.rfilter = filters[0];
    film.filter = filter_json(im, *filters[0]);
  }
  std::string pixels = lower(text(*f, "pixel_format", "rgb"));
  if (pixels != "rgb" && pixels != "rgba")
    im.warn(place_of(*f, "pixel_format"),
            f->label() + ": pixel_format " + quote(pixels) + " is not supported: pathcl writes RGB");
  if (f->type == "ldrfilm") {
    consume(*f, {"tonemap_method", "gamma", "exposure", "key", "burn"});
    im.warn(
        f->place,
        f->label() + ": its tone mapping is not applied: pathcl writes linear radiance (EXR; an sRGB PNG with --png)");
  }
  // Output choices that leave the pixels' values as they are.
  consume(*f, {"file_format", "component_format", "banner", "high_quality_edges", "sample_border", "compensate",
               "attach_log"});
  warn_unused(im, *f);
  return film;
}

// Mitsuba's horizontal field of view in degrees, from fov and fov_axis, or from a 35 mm focal length
// (50mm by default), for a film of this aspect ratio (src/render/sensor.cpp, parse_fov).
double horizontal_fov(const Object& s, double aspect) {
  std::optional<double> fov = optional_number(s, "fov");
  const Property* focal = find(s, "focal_length");
  if (fov && focal) fail(s.place, s.label() + ": give either fov or focal_length");
  double value;
  std::string axis;
  if (fov) {
    value = *fov;
    axis = lower(text(s, "fov_axis", "x"));
    if (axis == "smaller") axis = aspect > 1 ? "y" : "x";
    if (axis == "larger") axis = aspect > 1 ? "x" : "y";
  } else {
    std::string f = "50mm";
    if (focal && focal->kind == Kind::text)
      f = focal->text;
    else if (focal && (focal->kind == Kind::number || focal->kind == Kind::integer))
      f = std::to_string(focal->number);
    else if (focal)
      wrong_kind(s, *focal, "a <string> such as \"50mm\"");
    if (f.size() > 2 && f.substr(f.size() - 2) == "mm") f.resize(f.size() - 2);
    std::optional<double> mm = parse_double(f);
    if (!mm || !(*mm > 0))
      fail(focal->place, s.label() + ": focal_length " + quote(f + "mm") + ", expected a length such as \"50mm\"");
    value = 2 * glm::degrees(std::atan(std::sqrt(36.0 * 36.0 + 24.0 * 24.0) / (2 * *mm)));
    axis = "diagonal";
  }
  const double half = glm::radians(value) / 2;
  double x;
  if (axis == "x") {
    x = value;
  } else if (axis == "y") {
    x = glm::degrees(2 * std::atan(std::tan(half) * aspect));
  } else if (axis == "diagonal") {
    x = glm::degrees(2 * std::atan(std::tan(half) / std::sqrt(1 + 1 / (aspect * aspect))));
  } else {
    fail(place_of(s, "fov_axis"),
         s.label() + ": fov_axis " + quote(axis) + " (expected x, y, diagonal, smaller or larger)");
  }
  if (!(x > 0 && x < 180))
    fail(place_of(s, fov ? "fov" : "focal_length"), s.label() + ": the field of view must lie in (0, 180) degrees");
  return x;
}

// Mitsuba rounds some samplers' sample counts up to the grids they stratify (src/samplers/*.cpp).
long long stratified_sample_count(const std::string& type, long long n) {
  if (type == "stratified") {
    long long r = 1;
    while (r * r < n) ++r;
    return r * r;
  }
  if (type == "multijitter") {
    long long rows = (long long)std::sqrt(double(n));
    return ((n + rows - 1) / rows) * rows;
  }
  if (type == "orthogonal") {
    auto prime = [](long long x) {
      for (long long i = 2; i <= x / 2; ++i)
        if (x % i == 0) return false;
      return true;
    };
    long long r = 2;
    while (r * r < n || !prime(r)) ++r;
    return r * r;
  }
  if (type == "ldsampler") {
    long long r = 2;
    while (r * r < n) r *= 2;
    return r * r;
  }
  return n;
}

void read_sampler(Importer& im, const Object* s, json& render) {
  render["spp"] = 4u;  // Mitsuba's default sampler: independent, 4 samples a pixel, seed 0
  render["seed"] = 0u;
  render["sampler"] = "independent";
  if (!s) return;
  static const std::map<std::string, std::string> kSamplers = {{"independent", "independent"},
                                                               {"stratified", "stratified"},
                                                               {"multijitter", "stratified"},
                                                               {"orthogonal", "stratified"},
                                                               {"ldsampler", "sobol"},
                                                               {"hammersley", "sobol"},
                                                               {"sobol", "sobol"},
                                                               {"halton", "halton"}};
  auto it = kSamplers.find(s->type);
  if (it == kSamplers.end())
    fail(s->place, "sampler " + quote(s->type) +
                       " is not supported (supported: independent, stratified, multijitter, orthogonal, ldsampler; "
                       "0.6: halton, hammersley, sobol)");
  long long n = integer(*s, "sample_count", 4);
  if (n < 1) fail(place_of(*s, "sample_count"), s->label() + ": sample_count must be at least 1");
  if (n > (1 << 24))
    fail(place_of(*s, "sample_count"),
         s->label() + ": sample_count " + std::to_string(n) + " is above pathcl's largest, 16777216");
  long long rounded = std::min<long long>(stratified_sample_count(s->type, n), 1 << 24);
  if (rounded != n)
    im.warn(place_of(*s, "sample_count"), s->label() + ": sample_count " + std::to_string(n) + " becomes " +
                                              std::to_string(rounded) + ", as Mitsuba rounds it");
  long long seed = integer(*s, "seed", 0);
  if (seed < 0 || seed > 4294967295LL) fail(place_of(*s, "seed"), s->label() + ": seed must be in [0, 2^32 - 1]");
  render["spp"] = uint64_t(rounded);
  render["seed"] = uint64_t(seed);
  render["sampler"] = it->second;
  if (it->second != s->type)
    im.warn(s->place, s->label() + " becomes pathcl's " + quote(it->second) +
                          " sampler: another sample pattern, the same expected image");
  if (!boolean(*s, "jitter", true))
    im.warn(place_of(*s, "jitter"),
            s->label() + ": jitter false is not supported: pathcl's samples are always jittered");
  consume(*s, {"strength", "scramble", "dimension"});
  warn_unused(im, *s);
}

// Mitsuba's max_depth counts path vertices (1: emitters seen directly, 2: direct lighting); pathcl's the
// scattering events (0: emitters seen directly, 1: direct lighting).
uint64_t pathcl_depth(Importer& im, const Object& it, long long fallback) {
  const long long depth = integer(it, "max_depth", fallback);
  const Place at = place_of(it, "max_depth");
  if (depth == -1) {
    im.warn(at, it.label() +
                    ": max_depth -1 (unbounded) becomes pathcl's largest, 1024 scattering events (Russian roulette "
                    "ends paths long before)");
    return 1024;
  }
  if (depth == 0) fail(at, it.label() + ": max_depth 0 renders nothing; expected -1 (unbounded) or at least 1");
  if (depth < -1)
    fail(at, it.label() + ": max_depth " + std::to_string(depth) + ", expected -1 (unbounded) or at least 1");
  if (depth - 1 > 1024) {
    im.warn(at,
            it.label() + ": max_depth " + std::to_string(depth) + " becomes pathcl's largest, 1024 scattering events");
    return 1024;
  }
  return uint64_t(depth - 1);
}

void hide_emitters(Importer& im, const Object& it) {
  if (boolean(it, "hide_emitters", false))
    im.warn(place_of(it, "hide_emitters"),
            it.label() + ": hide_emitters is not supported: pathcl shows the emitters the camera sees directly");
}

const Object* read_integrator(Importer& im, const Object* it, json& render) {
  if (!it) {
    render["integrator"] = "path";
    render["max_depth"] = 1024u;
    return nullptr;
  }
  const std::string& t = it->type;
  if (t == "aov" || t == "moment" || t == "adaptive" || t == "irrcache") {  // wrappers around one integrator
    std::vector<const Object*> inner = nested(im, *it, "integrator");
    if (inner.empty()) fail(it->place, it->label() + ": expected a nested <integrator>");
    im.warn(it->place, it->label() + " is not supported: its nested " + inner[0]->label() + " renders the image" +
                           (t == "aov" ? " (pathcl's AOVs: render.aovs or --aov)" : ""));
    consume(*it, {"aovs", "max_error", "pval_threshold", "max_sample_factor"});
    warn_unused(im, *it);
    return read_integrator(im, inner[0], render);
  }
  if (t == "path" || t == "volpath" || t == "volpathmis" || t == "volpath_simple") {
    render["integrator"] = "path";
    render["max_depth"] = pathcl_depth(im, *it, -1);
    hide_emitters(im, *it);
    consume(*it, {"rr_depth", "strict_normals"});
  } else if (t == "direct") {
    render["integrator"] = "path";
    render["max_depth"] = 1u;  // emitters seen directly and direct lighting
    long long shading = integer(*it, "shading_samples", 1);
    long long emitter = integer(*it, "emitter_samples", shading), bsdf = integer(*it, "bsdf_samples", shading);
    if (emitter != 1 || bsdf != 1)
      im.warn(it->place, it->label() + ": " + std::to_string(emitter) + " emitter and " + std::to_string(bsdf) +
                             " bsdf samples per camera ray become one of each (pathcl's path tracer at max_depth 1): "
                             "the same expected image");
    hide_emitters(im, *it);
  } else if (t == "bdpt") {
    render["integrator"] = "bdpt";
    render["max_depth"] = pathcl_depth(im, *it, -1);
    consume(*it, {"rr_depth", "light_image", "sample_direct"});
  } else if (t == "ptracer") {
    render["integrator"] = "light";
    render["max_depth"] = pathcl_depth(im, *it, -1);
    im.warn(it->place, it->label() +
                           " becomes pathcl's light tracer, which does not see emitters directly nor anything through "
                           "mirrors and glass");
    hide_emitters(im, *it);
    consume(*it, {"rr_depth", "samples_per_pass"});
  } else {
    fail(it->place,
         "integrator " + quote(t) +
             " is not supported (supported: path, volpath and volpathmis without media, direct, bdpt, ptracer; "
             "aov and moment through their nested integrator)");
  }
  warn_unused(im, *it);
  return it;
}

void convert_sensor(Importer& im, const Object& s, json& camera, json& render) {
  if (s.type != "perspective" && s.type != "thinlens")
    fail(s.place, "sensor " + quote(s.type) + " is not supported (supported: perspective, thinlens)");
  std::vector<const Object*> films = nested(im, s, "film"), samplers = nested(im, s, "sampler");
  const Film film = read_film(im, films.empty() ? nullptr : films[0]);
  read_sampler(im, samplers.empty() ? nullptr : samplers[0], render);

  // Mitsuba's camera looks along +z of to_world, +y up; its image x axis runs along -x.
  const glm::dmat4 m = transform(s, "to_world");
  if (!is_orthonormal(glm::dmat3(m)))
    fail(place_of(s, "to_world"),
         s.label() + ": to_world scales or shears (Mitsuba refuses scale factors in a camera's transform too)");
  const glm::dvec3 position = transform_point(m, glm::dvec3(0));
  const glm::dvec3 forward = glm::normalize(transform_vector(m, {0, 0, 1}));
  const glm::dvec3 up = glm::normalize(transform_vector(m, {0, 1, 0}));
  const glm::dvec3 right = transform_vector(m, {-1, 0, 0});
  const double aspect = double(film.width) / film.height;
  const double fov_y = glm::degrees(2 * std::atan(std::tan(glm::radians(horizontal_fov(s, aspect)) / 2) / aspect));
  camera = camera_frame_json(position, forward, up, right);  // a mirroring to_world is left-handed
  camera["type"] = "perspective";
  camera["fov_y_degrees"] = fov_y;
  camera["width"] = unsigned(film.width);
  camera["height"] = unsigned(film.height);
  camera["filter"] = film.filter;
  if (s.type == "thinlens") {
    std::optional<double> aperture = optional_number(s, "aperture_radius");
    if (!aperture) fail(s.place, s.label() + ": needs an aperture_radius");
    camera["type"] = "thin_lens";
    camera["aperture_radius"] = *aperture;
    camera["focus_distance"] = number(s, "focus_distance", number(s, "far_clip", 1e4));  // Mitsuba: far_clip by default
  }
  std::optional<double> near_clip = optional_number(s, "near_clip"), far_clip = optional_number(s, "far_clip");
  if ((near_clip && *near_clip != 0.01) || (far_clip && *far_clip != 1e4))
    im.warn(place_of(s, near_clip ? "near_clip" : "far_clip"),
            s.label() +
                ": near_clip and far_clip are not supported: pathcl does not clip (Mitsuba hides surfaces nearer than "
                "near_clip or beyond far_clip)");
  if (number(s, "principal_point_offset_x", 0) != 0 || number(s, "principal_point_offset_y", 0) != 0)
    fail(place_of(s, "principal_point_offset_x"),
         s.label() + ": principal_point_offset is not supported (pathcl's camera looks through the image centre)");
  if (find(s, "srf"))
    fail(place_of(s, "srf"), s.label() + ": a spectral response function is not supported (pathcl renders RGB)");
  // A shutter interval blurs only what moves, and nothing moves in pathcl's scenes.
  consume(s, {"shutter_open", "shutter_close", "shutter_open_time"});
  im.origin("camera", s);
  if (film.film) {
    im.origin("camera.width", *film.film);
    im.origin("camera.height", *film.film);
  }
  if (film.rfilter) im.origin("camera.filter", *film.rfilter);
  if (!samplers.empty())
    for (const char* key : {"render.spp", "render.seed", "render.sampler"}) im.origin(key, *samplers[0]);
  warn_unused(im, s);
}

}  // namespace

ImportedScene import_mitsuba_xml(const std::string& path, const std::string& text, const SceneDefines& defines) {
  Importer im;
  // Given values win over the file's <default>s, which then leave them as they are.
  for (const auto& [name, value] : defines) {
    if (name.empty() || name.find_first_of("$\"<>= ") != std::string::npos)
      throw SceneError("-D " + name + "=" + value + ": expected NAME=VALUE with a parameter name");
    im.doc.defaults.emplace_back("$" + name, value);
  }
  im.scene_dir = fs::path(path).parent_path();
  if (im.scene_dir.empty()) im.scene_dir = ".";  // a file in the current directory
  im.doc.include_chain.push_back(path);
  std::error_code error;
  fs::path key = fs::weakly_canonical(path, error);
  im.doc.include_keys.push_back(error ? fs::absolute(path).lexically_normal() : key);
  parse_file(im.doc, path, text, std::nullopt, "");
  for (const auto& [id, index] : im.doc.ids) im.names.insert(id);

  const Object& scene = im.doc.objects[0];
  const Object* sensor = nullptr;
  const Object* integrator = nullptr;
  std::vector<const Object*> objects;
  for (const Property& p : scene.props) {
    if (!is_object(p)) continue;
    p.used = true;
    const Object& o = resolve(im, p);
    if (o.tag == "sensor" || o.tag == "integrator") {
      const Object*& first = o.tag == "sensor" ? sensor : integrator;
      if (first)
        im.warn(o.place,
                o.label() + ": only the first " + o.tag + " is used (" + first->place.str() + "); this one is ignored");
      else
        first = &o;
    } else if (o.tag == "medium" || o.tag == "phase" || o.tag == "volume") {
      fail(o.place, o.label() + ": media are not supported (pathcl renders surfaces in a vacuum)");
    } else {
      objects.push_back(&o);
    }
  }
  // Shapes, emitters and bsdfs in document order; textures, films, samplers and filters are read where
  // they are used.
  // A top-level area emitter with an id is the shapes' that refer to it (mitsuba-data's cbox-rgb.xml),
  // before or after them in the file.
  for (const Object* o : objects) {
    if (o->tag == "shape")
      convert_shape(im, *o, glm::dmat4(1.0));
    else if (o->tag == "emitter" && !(o->type == "area" && !o->id.empty()))
      convert_emitter(im, *o);
    else if (o->tag == "bsdf")
      material_for(im, *o);
  }
  for (const Object* o : objects)
    if (o->tag == "emitter" && o->type == "area" && !o->id.empty() && !im.attached_emitters.count(o->index))
      fail(o->place, o->label() + " is on no shape (an area emitter emits from the shape that refers to it)");
  if (!sensor)
    fail(scene.place, "the scene has no <sensor> (pathcl needs a camera: add a <sensor type=\"perspective\">)");
  json camera, render;
  convert_sensor(im, *sensor, camera, render);
  if (const Object* used = read_integrator(im, integrator, render)) {
    im.origin("render", *used);
  } else {
    im.origin("render", *sensor);
    im.warn(
        scene.place,
        "no <integrator>: Mitsuba's default path tracer, max_depth -1 (unbounded), becomes pathcl's path tracer at its "
        "largest max_depth, 1024 scattering events (Russian roulette ends paths long before)");
  }
  warn_unused(im, scene);

  json scene_json = {{"camera", camera}, {"materials", im.materials}, {"shapes", im.shapes}, {"render", render}};
  if (!im.lights.empty()) scene_json["lights"] = im.lights;
  im.out.scene = std::move(scene_json);
  return std::move(im.out);
}
