// pbrt-v4 scene files as pathcl scenes (scene/scene_import.h). docs/scene-format.md ("pbrt-v4 scenes") lists the rules: what
// maps exactly, what is approximated (each time with a warning naming the place) and what is refused.
//
// Reading follows pbrt-v4's parser and scene builder (src/pbrt/parser.cpp, scene.cpp): its tokens and
// parameter lists, the graphics state that AttributeBegin/End save and restore, the current transformation
// matrix (CTM) that every transform directive post-multiplies, and the named materials, textures and
// objects, resolved by name once every file is read. Translating follows its cameras, lights, materials and
// shapes (cameras.cpp, lights.cpp, materials.cpp, shapes.cpp, textures.cpp): where pbrt-v4 and its file
// format documentation differ, the code wins, since the scenes were made to look right in it.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <glm/geometric.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/type_ptr.hpp>
#include <glm/mat3x3.hpp>
#include <glm/mat4x4.hpp>
#include <glm/matrix.hpp>
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

#include <ImfChromaticitiesAttribute.h>
#include <ImfHeader.h>
#include <ImfInputFile.h>

#include "scene/input_file.h"
#include "scene/scene_error.h"
#include "scene/scene_import.h"
#include "scene/spectrum.h"
#include "scene/texture_load.h"

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

constexpr double kPi = 3.14159265358979323846;

// ---------------------------------------------------------------------------------------------------------
// Places and messages

struct Place {
  std::string file;  // the file as messages name it
  int line = 0;
  fs::path dir;      // the directory of that file
  // Line 0: the file as a whole (pbrt-v4's defaults for what it does not say).
  std::string str() const { return line ? file + ":" + std::to_string(line) : file; }
};

[[noreturn]] void fail(const Place& at, const std::string& what) { throw SceneError(at.str() + ": " + what); }

std::string num(double v) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%g", v);
  return buffer;
}

std::string in_quotes(const std::string& s) { return "\"" + s + "\""; }

std::string join(const std::vector<std::string>& words, const std::string& separator = ", ") {
  std::string out;
  for (size_t i = 0; i < words.size(); ++i) out += (i ? separator : "") + words[i];
  return out;
}

bool one_of(const std::string& word, const std::vector<std::string>& words) {
  return std::find(words.begin(), words.end(), word) != words.end();
}

// Warnings, each once ("FILE:LINE: what").
struct Messages {
  std::vector<std::string> warnings;
  std::set<std::string> seen;
};

void warn(Messages& m, const Place& at, const std::string& what) {
  std::string text = at.str() + ": " + what;
  if (m.seen.insert(text).second) m.warnings.push_back(text);
}

// ---------------------------------------------------------------------------------------------------------
// Tokens (pbrt-v4's Tokenizer): words, quoted strings with C escapes, '[' and ']'; '#' starts a comment that
// runs to the end of the line.

struct Token {
  std::string text;  // a quoted string without its quotes, escapes decoded
  bool quoted = false;
  int line = 0;
  int file = 0;  // index into the parser's file names
};

bool is_delimiter(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '"' || c == '[' || c == ']'; }

// A file being read, token by token (a large mesh is never held as tokens).
struct Scanner {
  std::string text;
  size_t pos = 0;
  int line = 1;
  int file = 0;  // index into the parser's file names
  std::string display;
  fs::path dir;
  Place here() const { return Place{display, line, dir}; }
};

Scanner scanner(std::string text, const std::string& display, const fs::path& dir, int file) {
  if (text.size() >= 2 && ((uint8_t(text[0]) == 0xfe && uint8_t(text[1]) == 0xff) ||
                           (uint8_t(text[0]) == 0xff && uint8_t(text[1]) == 0xfe)))
    throw SceneError(display + ": the file is UTF-16 text, expected a pbrt scene in ASCII or UTF-8");
  Scanner s;
  s.pos = text.rfind("\xef\xbb\xbf", 0) == 0 ? 3 : 0;
  s.text = std::move(text);
  s.file = file;
  s.display = display;
  s.dir = dir;
  return s;
}

// The next token, or none at the end of the file.
std::optional<Token> scan_token(Scanner& s) {
  const std::string& text = s.text;
  size_t& i = s.pos;
  while (i < text.size()) {
    char c = text[i];
    if (c == '\n' || c == '\r') {
      ++s.line;
      i += (c == '\r' && i + 1 < text.size() && text[i + 1] == '\n') ? 2 : 1;
    } else if (c == ' ' || c == '\t') {
      ++i;
    } else if (c == '#') {
      while (i < text.size() && text[i] != '\n' && text[i] != '\r') ++i;
    } else if (c == '[' || c == ']') {
      ++i;
      return Token{std::string(1, c), false, s.line, s.file};
    } else if (c == '"') {
      Token t{"", true, s.line, s.file};
      for (++i;; ++i) {
        if (i >= text.size() || text[i] == '\n' || text[i] == '\r')
          fail(s.here(), "unterminated string (a quoted string ends on the line where it starts)");
        if (text[i] == '"') break;
        if (text[i] != '\\') {
          t.text += text[i];
          continue;
        }
        char e = ++i < text.size() ? text[i] : '\n';
        const char* from = "bfnrt\\'\"";
        const char* to = "\b\f\n\r\t\\'\"";
        const char* found = e ? std::strchr(from, e) : nullptr;
        if (!found) fail(s.here(), std::string("unknown escape \\") + (e == '\n' ? std::string("") : std::string(1, e)) +
                                       " in a string (expected \\b, \\f, \\n, \\r, \\t, \\\\, \\' or \\\")");
        t.text += to[found - from];
      }
      ++i;
      return t;
    } else {
      size_t start = i;
      while (i < text.size() && !is_delimiter(text[i])) ++i;
      return Token{text.substr(start, i - start), false, s.line, s.file};
    }
  }
  return std::nullopt;
}

// The files that tokens come from, by index: how messages name them and their directories.
struct FileNames {
  std::vector<std::pair<std::string, fs::path>> list;
  Place at(const Token& t) const { return Place{list[t.file].first, t.line, list[t.file].second}; }
};

// A number as pbrt-v4 reads one (decimal or hexadecimal floating point), finite.
double parse_number(const FileNames& names, const Token& t, const std::string& context) {
  const char* begin = t.text.c_str();
  char* end = nullptr;
  double v = t.quoted || t.text.empty() ? 0 : std::strtod(begin, &end);
  if (t.quoted || t.text.empty() || end != begin + t.text.size())
    fail(names.at(t), "expected a number" + context + ", got " + (t.quoted ? in_quotes(t.text) : t.text));
  if (!std::isfinite(v)) fail(names.at(t), "the number " + t.text + context + " is not finite");
  return v;
}

// ---------------------------------------------------------------------------------------------------------
// Parameters: "TYPE NAME" followed by a value or a [list] of values.

// pbrt-v4's parameter types; pbrt-v3's spellings point, vector, color and normal3 are read as point3, vector3,
// rgb and normal.
const std::vector<std::string> kParameterTypes = {"integer", "float",  "point2", "vector2", "point3",
                                                  "vector3", "normal", "bool",   "string",  "texture",
                                                  "rgb",     "spectrum", "blackbody"};

std::string canonical_type(const std::string& type) {
  if (type == "point") return "point3";
  if (type == "vector") return "vector3";
  if (type == "color") return "rgb";
  if (type == "normal3") return "normal";
  return type;
}

struct Param {
  std::string type;          // canonical
  std::string written_type;  // as the file wrote it
  std::string name;
  Place place;
  std::vector<double> numbers;
  std::vector<std::string> strings;
  std::vector<bool> bools;
  bool from_attribute = false;  // a default that Attribute set
  mutable bool used = false;
  std::string decl() const { return in_quotes(written_type + " " + name); }
};

// A directive's parameters, then the defaults Attribute set for its kind, the later ones first: the first of
// a name wins (pbrt-v4's ParameterDictionary).
struct Params {
  std::vector<Param> list;
};

// Checks one parameter's values against its type, as pbrt-v4's ParameterDictionary does.
void check_values(Param& p) {
  if (!one_of(p.type, kParameterTypes))
    fail(p.place, "unknown parameter type " + in_quotes(p.written_type) + " in " + p.decl() + " (expected " +
                      join(kParameterTypes) + ")");
  int kinds = !p.numbers.empty() + !p.strings.empty() + !p.bools.empty();
  if (kinds == 0) fail(p.place, p.decl() + " has no values");
  if (kinds > 1) fail(p.place, p.decl() + " mixes numbers, strings and true/false");
  if (p.type == "bool") {
    for (const std::string& s : p.strings) {
      if (s != "true" && s != "false") fail(p.place, p.decl() + ": expected true or false, got " + in_quotes(s));
      p.bools.push_back(s == "true");
    }
    p.strings.clear();
    if (p.bools.empty()) fail(p.place, p.decl() + ": expected true or false");
  } else if (p.type == "string" || p.type == "texture") {
    if (p.strings.empty()) fail(p.place, p.decl() + ": expected a quoted string");
  } else if (p.type == "spectrum") {
    if (!p.bools.empty()) fail(p.place, p.decl() + ": expected [wavelength value ...] pairs or a spectrum's name");
  } else if (p.numbers.empty()) {
    fail(p.place, p.decl() + ": expected numbers, got " + (p.strings.empty() ? "true/false" : "a string"));
  }
  if (p.type == "integer")
    for (double v : p.numbers)
      if (v != std::floor(v) || std::abs(v) > 2147483647.0)
        fail(p.place, p.decl() + ": expected integers, got " + num(v));
  size_t per = p.type == "point2" || p.type == "vector2" ? 2
               : p.type == "point3" || p.type == "vector3" || p.type == "normal" || p.type == "rgb" ? 3
               : p.type == "spectrum" && !p.numbers.empty() ? 2
                                                             : 1;
  if (p.numbers.size() % per != 0)
    fail(p.place, p.decl() + ": expected a multiple of " + std::to_string(per) + " values, got " +
                      std::to_string(p.numbers.size()));
}

// The parameter `name` of one of `types`, marked used; nullptr if not given. An Attribute default of another
// type is passed over; the directive's own parameter of another type is an error.
const Param* lookup(const Params& ps, const std::string& what, const std::string& name,
                    const std::vector<std::string>& types) {
  for (const Param& p : ps.list) {
    if (p.name != name) continue;
    if (one_of(p.type, types)) {
      p.used = true;
      return &p;
    }
    if (p.from_attribute) continue;
    std::vector<std::string> expected;
    for (const std::string& t : types) expected.push_back(in_quotes(t + " " + name));
    fail(p.place, p.decl() + ": " + what + " takes " + join(expected, " or "));
  }
  return nullptr;
}

// Reading one value of a parameter.
const Param* one_value(const Param* p) {
  size_t n = p->type == "point3" || p->type == "vector3" || p->type == "normal" || p->type == "rgb" ? 3 : 1;
  size_t count = p->numbers.size() + p->strings.size() + p->bools.size();
  if (p->type != "spectrum" && count != n)
    fail(p->place, p->decl() + ": expected " + (n == 1 ? std::string("one value") : std::to_string(n) + " values") +
                       ", got " + std::to_string(count));
  return p;
}

double get_float(const Params& ps, const std::string& what, const std::string& name, double fallback) {
  const Param* p = lookup(ps, what, name, {"float"});
  return p ? one_value(p)->numbers[0] : fallback;
}

int get_int(const Params& ps, const std::string& what, const std::string& name, int fallback) {
  const Param* p = lookup(ps, what, name, {"integer"});
  return p ? int(one_value(p)->numbers[0]) : fallback;
}

bool get_bool(const Params& ps, const std::string& what, const std::string& name, bool fallback) {
  const Param* p = lookup(ps, what, name, {"bool"});
  return p ? one_value(p)->bools[0] : fallback;
}

std::string get_string(const Params& ps, const std::string& what, const std::string& name,
                       const std::string& fallback) {
  const Param* p = lookup(ps, what, name, {"string"});
  return p ? one_value(p)->strings[0] : fallback;
}

glm::dvec3 get_point(const Params& ps, const std::string& what, const std::string& name, glm::dvec3 fallback) {
  const Param* p = lookup(ps, what, name, {"point3"});
  if (!p) return fallback;
  one_value(p);
  return {p->numbers[0], p->numbers[1], p->numbers[2]};
}

std::vector<double> get_floats(const Params& ps, const std::string& what, const std::string& name) {
  const Param* p = lookup(ps, what, name, {"float"});
  return p ? p->numbers : std::vector<double>{};
}

std::vector<glm::dvec3> get_vec3s(const Params& ps, const std::string& what, const std::string& name,
                                  const std::vector<std::string>& types) {
  std::vector<glm::dvec3> out;
  if (const Param* p = lookup(ps, what, name, types))
    for (size_t i = 0; i + 2 < p->numbers.size(); i += 3) out.push_back({p->numbers[i], p->numbers[i + 1], p->numbers[i + 2]});
  return out;
}

// Texture coordinates: "point2 uv" (pbrt-v4), or pbrt-v3's "float uv" and "st" spellings, as pairs.
std::vector<glm::dvec2> get_uvs(const Params& ps, const std::string& what) {
  std::vector<glm::dvec2> out;
  const Param* p = lookup(ps, what, "uv", {"point2", "float"});
  if (!p) p = lookup(ps, what, "st", {"point2", "float"});
  if (!p) return out;
  if (p->numbers.size() % 2) fail(p->place, p->decl() + ": expected (u, v) pairs, got " + std::to_string(p->numbers.size()) + " values");
  for (size_t i = 0; i + 1 < p->numbers.size(); i += 2) out.push_back({p->numbers[i], p->numbers[i + 1]});
  return out;
}

std::vector<int> get_ints(const Params& ps, const std::string& what, const std::string& name) {
  std::vector<int> out;
  if (const Param* p = lookup(ps, what, name, {"integer"}))
    for (double v : p->numbers) out.push_back(int(v));
  return out;
}

// The directive's own parameters that nothing read: pbrt-v4 does not know them there either.
void warn_unused(Messages& m, const Params& ps, const std::string& what) {
  for (const Param& p : ps.list)
    if (!p.used && !p.from_attribute) warn(m, p.place, what + ": unknown parameter " + p.decl() + " ignored");
}

// ---------------------------------------------------------------------------------------------------------
// What the files say, read by the parser below and translated by the functions after it.

// A directive with a type name and parameters: Camera "perspective" ..., Shape "sphere" ...
struct Entity {
  std::string directive, type;
  Place place;
  Params params;
  std::string what() const { return directive + " " + in_quotes(type); }
};

struct ShapeEntity {
  Entity entity;
  glm::dmat4 ctm{1.0};
  bool reverse_orientation = false;
  int material = 0;            // index into Scene::materials, unless named_material is set
  std::string named_material;  // NamedMaterial, resolved once every file is read
  Place named_material_place;
  std::optional<Entity> area_light;
  std::string inside_medium, outside_medium;
  Place medium_place;
};

struct MaterialEntity {
  Entity entity;  // directive Material or MakeNamedMaterial; type = the material type
  std::string name;  // of a named material
};

struct TextureEntity {
  Entity entity;  // type = the texture class (imagemap, ...)
  std::string name;
  bool spectrum = true;  // "spectrum" (or pbrt-v3's "color") texture, else "float"
};

struct LightEntity {
  Entity entity;
  glm::dmat4 ctm{1.0};
  std::string medium;
};

struct InstanceUse {
  std::string name;
  glm::dmat4 ctm{1.0};
  Place place;
};

// The world in file order: a shape, or a use of an object's shapes.
struct WorldItem {
  int shape = -1;
  int instance = -1;
};

struct Scene {
  std::optional<Entity> camera, film, sampler, integrator, filter;
  glm::dmat4 camera_from_world{1.0};
  std::string camera_medium;
  std::optional<long long> option_seed;
  Place option_seed_place;
  std::vector<MaterialEntity> materials;  // [0]: pbrt-v4's default, a diffuse material
  std::map<std::string, int> named_materials;
  std::map<std::string, TextureEntity> float_textures, spectrum_textures;
  std::vector<ShapeEntity> shapes;
  std::vector<InstanceUse> instance_uses;
  std::vector<WorldItem> world;
  std::map<std::string, std::vector<ShapeEntity>> objects;
  std::map<std::string, Place> object_places;
  std::vector<LightEntity> lights;
  std::map<std::string, Place> media;
};

// ---------------------------------------------------------------------------------------------------------
// Transforms, as pbrt-v4 builds them (util/transform.cpp). glm matrices are column-major: m[column][row].

glm::dmat4 rotate_matrix(double degrees, glm::dvec3 axis, const Place& at) {
  if (glm::length(axis) == 0) fail(at, "Rotate about the zero vector (expected a non-zero axis)");
  return glm::rotate(glm::dmat4(1.0), degrees * kPi / 180, glm::normalize(axis));
}

// pbrt-v4's LookAt: the camera-from-world transform of a camera at `eye` looking at `look`. Its camera space
// has +x = cross(up, view direction), so seen from the camera +x is the image's right and the frame is
// left-handed.
glm::dmat4 look_at_matrix(glm::dvec3 eye, glm::dvec3 look, glm::dvec3 up, const Place& at) {
  glm::dvec3 dir = look - eye;
  if (glm::length(dir) == 0) fail(at, "LookAt: the eye and the point looked at coincide");
  dir = glm::normalize(dir);
  if (glm::length(up) == 0 || glm::length(glm::cross(glm::normalize(up), dir)) == 0)
    fail(at, "LookAt: the up vector is zero or parallel to the viewing direction");
  glm::dvec3 right = glm::normalize(glm::cross(glm::normalize(up), dir));
  glm::dvec3 new_up = glm::cross(dir, right);
  glm::dmat4 world_from_camera(glm::dvec4(right, 0), glm::dvec4(new_up, 0), glm::dvec4(dir, 0), glm::dvec4(eye, 1));
  return glm::inverse(world_from_camera);
}

// pbrt's Transform and ConcatTransform take the 16 numbers column by column (the translation last).
glm::dmat4 matrix_from_file(const std::vector<double>& v) { return glm::make_mat4(v.data()); }

bool is_affine(const glm::dmat4& m) { return m[0][3] == 0 && m[1][3] == 0 && m[2][3] == 0 && m[3][3] == 1; }

// How far a linear map is from a similarity (a rotation times a uniform scale, mirrored or not): the largest
// difference of its columns' lengths and of their products, relative to its scale; infinity when singular.
double similarity_error(const glm::dmat3& l) {
  double sx = glm::length(l[0]), sy = glm::length(l[1]), sz = glm::length(l[2]);
  double s = std::max({sx, sy, sz});
  if (!(std::min({sx, sy, sz}) > 0)) return HUGE_VAL;
  return std::max({std::abs(sx - sy) / s, std::abs(sx - sz) / s, std::abs(glm::dot(l[0], l[1])) / (sx * sy),
                   std::abs(glm::dot(l[0], l[2])) / (sx * sz), std::abs(glm::dot(l[1], l[2])) / (sy * sz)});
}

bool is_similarity(const glm::dmat3& l) { return similarity_error(l) <= 1e-5; }


// ---------------------------------------------------------------------------------------------------------
// The parser: directives in order, with the state pbrt-v4's BasicSceneBuilder keeps.

struct GraphicsState {
  glm::dmat4 ctm{1.0};
  bool reverse_orientation = false;
  int material = 0;
  std::string named_material;
  Place named_material_place;
  std::optional<Entity> area_light;
  std::vector<Param> shape_attributes, light_attributes, material_attributes, texture_attributes, medium_attributes;
  std::string inside_medium, outside_medium;
  Place medium_place;
  bool start_transform_active = true;  // ActiveTransform: only the start transform is kept
};

struct OpenFile {
  Scanner scanner;
  bool imported = false;  // an Import: the graphics state it changes is its own
  GraphicsState saved_state;
  size_t saved_depth = 0;
};

struct Parser {
  explicit Parser(Messages& m) : messages(m) {}
  Messages& messages;
  fs::path main_dir;
  FileNames names;
  std::vector<OpenFile> files;  // the innermost last
  std::optional<Token> pushed_back;
  Scene scene;
  GraphicsState state;
  std::vector<GraphicsState> saved_states;
  std::vector<std::pair<char, Place>> saved_kinds;  // 'a' AttributeBegin, 'o' ObjectBegin
  std::map<std::string, glm::dmat4> coordinate_systems;
  bool in_world = false;
  std::string object;  // the object being defined ("" outside ObjectBegin/End)
};

// Where a file that `from` names as `written` is (Include, Import, meshes, images, spectra): pbrt-v4
// resolves every relative path against the directory of the main scene file (util/file.cpp,
// ResolveFilename; SetSearchDirectory is called for the main file only), also those written in included
// files. A file found only beside the including file (a layout other tools assume) is taken from there,
// with a warning. Returns the path relative to the main directory (or absolute): as a pathcl scene beside
// the main file names it.
std::string resolve_path(Messages& m, const fs::path& main_dir, const std::string& written, const Place& from,
                         const std::string& what) {
  fs::path p = written;
  if (written.empty()) fail(from, what + ": the file name is empty");
  if (p.is_absolute()) {
    if (!fs::exists(p)) fail(from, what + ": cannot find " + in_quotes(written));
    return written;
  }
  if (fs::exists(main_dir / p)) return written;
  fs::path beside = from.dir / p;
  if (fs::exists(beside)) {
    std::string rebased = fs::proximate(beside, main_dir.empty() ? fs::path(".") : main_dir).generic_string();
    warn(m, from, what + ": " + in_quotes(written) + " is not in " + in_quotes(main_dir.empty() ? "." : main_dir.generic_string()) +
                      " (pbrt-v4 resolves relative paths against the main file's directory) but beside this file: "
                      "taken from there, as " + in_quotes(rebased));
    return rebased;
  }
  fail(from, what + ": cannot find " + in_quotes(written) + " (relative paths are resolved against " +
                 in_quotes(main_dir.empty() ? std::string(".") : main_dir.generic_string()) +
                 ", the directory of the main scene file, as pbrt-v4 does)");
}

// A path that resolve_path returned, as this process opens it.
fs::path openable(const fs::path& main_dir, const std::string& path) {
  return fs::path(path).is_absolute() ? fs::path(path) : main_dir / path;
}

std::string read_file(const fs::path& path, const Place& from, const std::string& what) {
  std::ifstream in(path, std::ios::binary);
  if (!in || fs::is_directory(path)) fail(from, what + ": cannot read " + in_quotes(path.generic_string()));
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

void open_file(Parser& p, const std::string& text, const std::string& display, const fs::path& dir, bool imported,
               const Place& directive) {
  if (p.files.size() >= 64) fail(directive, "Include and Import nest more than 64 files deep (does a file include itself?)");
  OpenFile f;
  p.names.list.push_back({display, dir});
  f.scanner = scanner(text, display, dir, int(p.names.list.size()) - 1);
  f.imported = imported;
  if (imported) {
    f.saved_state = p.state;
    f.saved_depth = p.saved_states.size();
  }
  p.files.push_back(std::move(f));
}

// Leaving a file that Import read: its AttributeBegins must be closed, and the graphics state is the
// importer's again (pbrt-v4 parses an Import with a copy of the state).
void close_file(Parser& p) {
  OpenFile& f = p.files.back();
  if (f.imported) {
    if (p.saved_states.size() != f.saved_depth)
      fail(p.saved_kinds.back().second, "AttributeBegin without an AttributeEnd in the imported file");
    p.state = f.saved_state;
  }
  p.files.pop_back();
}

// The next token of the file being read; a directive and its arguments never run on into the next file.
std::optional<Token> next_token(Parser& p) {
  if (p.pushed_back) return std::exchange(p.pushed_back, std::nullopt);
  if (p.files.empty()) return std::nullopt;
  return scan_token(p.files.back().scanner);
}

// The next directive's token, from whichever file is open (leaving the finished ones).
std::optional<Token> next_directive(Parser& p) {
  while (true) {
    if (std::optional<Token> t = next_token(p)) return t;
    if (p.files.empty()) return std::nullopt;
    close_file(p);
  }
}

// The next token, which must exist: `what` says what was expected after `after`.
Token required_token(Parser& p, const Place& after, const std::string& what) {
  std::optional<Token> t = next_token(p);
  if (!t) fail(after, "the file ends where " + what + " was expected");
  return *t;
}

std::string required_string(Parser& p, const Token& directive, const std::string& what) {
  Place at = p.names.at(directive);
  Token t = required_token(p, at, what + " after " + directive.text);
  if (!t.quoted) fail(p.names.at(t), directive.text + ": expected " + what + " in quotes, got " + t.text);
  return t.text;
}

std::vector<double> required_numbers(Parser& p, const Token& directive, int count) {
  std::vector<double> v;
  Place at = p.names.at(directive);
  for (int i = 0; i < count; ++i)
    v.push_back(parse_number(p.names, required_token(p, at, "a number after " + directive.text),
                             " (" + directive.text + " takes " + std::to_string(count) + " numbers)"));
  return v;
}

// Transform and ConcatTransform: [ 16 numbers ].
std::vector<double> required_matrix(Parser& p, const Token& directive) {
  Place at = p.names.at(directive);
  Token open = required_token(p, at, "[ after " + directive.text);
  if (open.quoted || open.text != "[") fail(p.names.at(open), directive.text + ": expected [ and 16 numbers");
  std::vector<double> v = required_numbers(p, directive, 16);
  Token close = required_token(p, at, "] after " + directive.text);
  if (close.quoted || close.text != "]") fail(p.names.at(close), directive.text + ": expected ] after 16 numbers");
  return v;
}

// A directive's parameter list: "TYPE NAME" value or "TYPE NAME" [ values ], as long as quoted strings follow.
std::vector<Param> parse_params(Parser& p, const std::string& what) {
  std::vector<Param> params;
  while (true) {
    std::optional<Token> t = next_token(p);
    if (!t) break;
    if (!t->quoted) {
      p.pushed_back = t;
      break;
    }
    Param prm;
    prm.place = p.names.at(*t);
    std::istringstream words(t->text);
    std::string extra;
    words >> prm.written_type >> prm.name;
    if (prm.name.empty() || (words >> extra))
      fail(prm.place, what + ": expected a parameter \"TYPE NAME\", got " + in_quotes(t->text));
    prm.type = canonical_type(prm.written_type);
    for (const Param& earlier : params)
      if (earlier.name == prm.name)
        fail(prm.place, what + ": parameter " + in_quotes(prm.name) + " is given twice (first at line " +
                            std::to_string(earlier.place.line) + ")");
    auto add_value = [&](const Token& v) {
      if (v.quoted)
        prm.strings.push_back(v.text);
      else if (v.text == "true" || v.text == "false")
        prm.bools.push_back(v.text == "true");
      else
        prm.numbers.push_back(parse_number(p.names, v, " in " + prm.decl()));
    };
    Token v = required_token(p, prm.place, "the value of " + prm.decl());
    if (!v.quoted && v.text == "[") {
      Place open = p.names.at(v);
      while (true) {
        Token e = required_token(p, open, "] closing the values of " + prm.decl());
        if (!e.quoted && e.text == "]") break;
        if (!e.quoted && e.text == "[") fail(p.names.at(e), prm.decl() + ": [ inside a list of values");
        add_value(e);
      }
    } else if (!v.quoted && v.text == "]") {
      fail(p.names.at(v), prm.decl() + ": ] without [");
    } else {
      add_value(v);
    }
    check_values(prm);
    params.push_back(std::move(prm));
  }
  return params;
}

// The parameters of a directive, with the Attribute defaults of its kind behind them.
Params with_defaults(std::vector<Param> own, const std::vector<Param>& defaults) {
  Params ps;
  ps.list = std::move(own);
  for (auto it = defaults.rbegin(); it != defaults.rend(); ++it) ps.list.push_back(*it);
  return ps;
}

Entity parse_entity(Parser& p, const Token& directive, const std::vector<Param>& defaults) {
  Entity e;
  e.directive = directive.text;
  e.place = p.names.at(directive);
  e.type = required_string(p, directive, "a type name");
  e.params = with_defaults(parse_params(p, e.what()), defaults);
  return e;
}

void require_options_block(const Parser& p, const Token& t) {
  if (p.in_world)
    fail(p.names.at(t), t.text + " belongs before WorldBegin (options cannot be set inside the world block)");
}

void require_world_block(const Parser& p, const Token& t) {
  if (!p.in_world)
    fail(p.names.at(t), t.text + " belongs after WorldBegin (the scene description is inside the world block)");
}

void check_type(const Entity& e, const std::vector<std::string>& known, const std::string& kind) {
  if (!one_of(e.type, known))
    fail(e.place, "unknown " + kind + " " + in_quotes(e.type) + " (pbrt-v4's: " + join(known) + ")");
}

const std::vector<std::string> kMaterialTypes = {"coateddiffuse", "coatedconductor", "conductor", "dielectric",
                                                 "diffuse", "diffusetransmission", "hair", "interface",
                                                 "measured", "mix", "subsurface", "thindielectric"};

void check_material_type(Messages& m, Entity& e) {
  if (e.type.empty() || e.type == "none") {
    warn(m, e.place, e.what() + " is pbrt-v3's spelling of \"interface\": read as \"interface\"");
    e.type = "interface";
  }
  static const std::vector<std::string> v3 = {"matte", "plastic", "metal", "glass", "mirror", "uber",
                                              "substrate", "translucent", "fourier", "disney", "kdsubsurface"};
  if (one_of(e.type, v3))
    fail(e.place, e.what() + " is a pbrt-v3 material (pbrt-v4's: " + join(kMaterialTypes) +
                      "; `pbrt --upgrade` converts a pbrt-v3 file)");
  check_type(e, kMaterialTypes, "material type");
}

// Applies a transform directive to the CTM: post-multiplied (or replacing it), and only to the start
// transform (motion blur is not rendered).
void apply_transform(Parser& p, const glm::dmat4& m, bool replace) {
  if (!p.state.start_transform_active) return;
  p.state.ctm = replace ? m : p.state.ctm * m;
}

void warn_motion(Parser& p, const Place& at, const std::string& what) {
  warn(p.messages, at, what + ": motion blur is not supported, the start transform is used for everything");
}

void add_shape(Parser& p, Entity e) {
  static const std::vector<std::string> known = {"sphere", "cylinder", "disk", "bilinearmesh", "curve",
                                                 "trianglemesh", "plymesh", "loopsubdiv"};
  static const std::vector<std::string> v3 = {"cone", "paraboloid", "hyperboloid", "nurbs", "heightfield"};
  if (one_of(e.type, v3)) fail(e.place, e.what() + " is a pbrt-v3 shape that pbrt-v4 does not have");
  check_type(e, known, "shape");
  ShapeEntity s;
  s.entity = std::move(e);
  s.ctm = p.state.ctm;
  s.reverse_orientation = p.state.reverse_orientation;
  s.material = p.state.material;
  s.named_material = p.state.named_material;
  s.named_material_place = p.state.named_material_place;
  s.area_light = p.state.area_light;
  s.inside_medium = p.state.inside_medium;
  s.outside_medium = p.state.outside_medium;
  s.medium_place = p.state.medium_place;
  if (!p.object.empty()) {
    p.scene.objects[p.object].push_back(std::move(s));
  } else {
    p.scene.world.push_back({int(p.scene.shapes.size()), -1});
    p.scene.shapes.push_back(std::move(s));
  }
}

void attribute_begin(Parser& p, char kind, const Place& at) {
  p.saved_states.push_back(p.state);
  p.saved_kinds.push_back({kind, at});
}

void attribute_end(Parser& p, char kind, const Token& t) {
  Place at = p.names.at(t);
  size_t floor = !p.files.empty() && p.files.back().imported ? p.files.back().saved_depth : 0;
  if (p.saved_states.size() <= floor)
    fail(at, t.text + " without a matching " + (kind == 'a' ? "AttributeBegin" : "ObjectBegin"));
  if (p.saved_kinds.back().first != kind)
    fail(at, t.text + " closes the " + (kind == 'a' ? "ObjectBegin" : "AttributeBegin") + " at " +
                 p.saved_kinds.back().second.str());
  p.state = p.saved_states.back();
  p.saved_states.pop_back();
  p.saved_kinds.pop_back();
}

// Include and Import: the file, read and tokenized, becomes the innermost open file.
void include_file(Parser& p, const Token& t, bool imported) {
  Place at = p.names.at(t);
  if (imported && !p.in_world) fail(at, "Import belongs after WorldBegin (Include reads a file anywhere)");
  std::string written = required_string(p, t, "a file name");
  std::string path = resolve_path(p.messages, p.main_dir, written, at, t.text);
  fs::path full = openable(p.main_dir, path);
  std::string display = fs::path(path).is_absolute() ? path : (p.main_dir / path).lexically_normal().generic_string();
  open_file(p, read_file(full, at, t.text), display, full.parent_path(), imported, at);
}

void parse_directive(Parser& p, const Token& t) {
  const std::string& d = t.text;
  const Place at = p.names.at(t);
  GraphicsState& gs = p.state;
  if (t.quoted) fail(at, "unexpected string " + in_quotes(d) + " where a directive was expected");
  if (d == "[" || d == "]") fail(at, "unexpected " + d + " where a directive was expected");

  if (d == "Identity") {
    apply_transform(p, glm::dmat4(1.0), true);
  } else if (d == "Translate") {
    std::vector<double> v = required_numbers(p, t, 3);
    apply_transform(p, glm::translate(glm::dmat4(1.0), glm::dvec3(v[0], v[1], v[2])), false);
  } else if (d == "Scale") {
    std::vector<double> v = required_numbers(p, t, 3);
    apply_transform(p, glm::scale(glm::dmat4(1.0), glm::dvec3(v[0], v[1], v[2])), false);
  } else if (d == "Rotate") {
    std::vector<double> v = required_numbers(p, t, 4);
    apply_transform(p, rotate_matrix(v[0], {v[1], v[2], v[3]}, at), false);
  } else if (d == "LookAt") {
    std::vector<double> v = required_numbers(p, t, 9);
    apply_transform(p, look_at_matrix({v[0], v[1], v[2]}, {v[3], v[4], v[5]}, {v[6], v[7], v[8]}, at), false);
  } else if (d == "Transform" || d == "ConcatTransform") {
    apply_transform(p, matrix_from_file(required_matrix(p, t)), d == "Transform");
  } else if (d == "CoordinateSystem") {
    p.coordinate_systems[required_string(p, t, "a name")] = gs.ctm;
  } else if (d == "CoordSysTransform") {
    std::string name = required_string(p, t, "a name");
    auto it = p.coordinate_systems.find(name);
    if (it == p.coordinate_systems.end())
      fail(at, "CoordSysTransform: no coordinate system " + in_quotes(name) +
                   " (CoordinateSystem names one; \"camera\" and \"world\" are predefined)");
    apply_transform(p, it->second, true);
  } else if (d == "ActiveTransform") {
    Token which = required_token(p, at, "All, StartTime or EndTime after ActiveTransform");
    if (which.quoted || (which.text != "All" && which.text != "StartTime" && which.text != "EndTime"))
      fail(p.names.at(which), "ActiveTransform: expected All, StartTime or EndTime, got " + which.text);
    if (which.text != "All") warn_motion(p, at, "ActiveTransform " + which.text);
    gs.start_transform_active = which.text != "EndTime";
  } else if (d == "TransformTimes") {
    require_options_block(p, t);
    required_numbers(p, t, 2);
    warn_motion(p, at, "TransformTimes");
  } else if (d == "ReverseOrientation") {
    require_world_block(p, t);
    gs.reverse_orientation = !gs.reverse_orientation;
  } else if (d == "Camera") {
    require_options_block(p, t);
    Entity e = parse_entity(p, t, {});
    check_type(e, {"perspective", "orthographic", "realistic", "spherical"}, "camera");
    p.scene.camera = std::move(e);
    p.scene.camera_from_world = gs.ctm;
    p.scene.camera_medium = gs.outside_medium;
    if (is_affine(gs.ctm) && glm::determinant(glm::dmat3(gs.ctm)) != 0)
      p.coordinate_systems["camera"] = glm::inverse(gs.ctm);
  } else if (d == "Film" || d == "Sampler" || d == "Integrator" || d == "PixelFilter" || d == "Accelerator") {
    require_options_block(p, t);
    Entity e = parse_entity(p, t, {});
    if (d == "Film") {
      check_type(e, {"rgb", "gbuffer", "spectral", "image"}, "film");
      p.scene.film = std::move(e);
    } else if (d == "Sampler") {
      check_type(e, {"zsobol", "sobol", "paddedsobol", "halton", "pmj02bn", "independent", "stratified",
                     "02sequence", "lowdiscrepancy", "maxmindist"},
                 "sampler");
      p.scene.sampler = std::move(e);
    } else if (d == "Integrator") {
      check_type(e, {"volpath", "path", "bdpt", "lightpath", "sppm", "simplepath", "simplevolpath", "randomwalk",
                     "ambientocclusion", "mlt", "aov", "function", "directlighting", "whitted"},
                 "integrator");
      p.scene.integrator = std::move(e);
    } else if (d == "PixelFilter") {
      check_type(e, {"box", "gaussian", "mitchell", "sinc", "lanczos", "triangle"}, "pixel filter");
      p.scene.filter = std::move(e);
    } else {
      warn(p.messages, at, e.what() + ": pathcl builds its own BVH, the accelerator settings are ignored");
    }
  } else if (d == "ColorSpace") {
    std::string name = required_string(p, t, "a colour space name");
    if (name != "srgb")
      fail(at, "ColorSpace " + in_quotes(name) + " is not supported (pathcl renders linear sRGB: \"srgb\" only)");
  } else if (d == "Option") {
    std::string name = required_string(p, t, "an option name");
    Token value = required_token(p, at, "the value of Option " + in_quotes(name));
    std::string bare = name.substr(name.find(' ') == std::string::npos ? 0 : name.rfind(' ') + 1);
    if (bare == "seed") {
      double seed = parse_number(p.names, value, " (Option \"seed\" takes an integer)");
      if (seed != std::floor(seed)) fail(p.names.at(value), "Option \"seed\": expected an integer, got " + value.text);
      p.scene.option_seed = (long long)seed;
      p.scene.option_seed_place = at;
    } else {
      warn(p.messages, at, "Option " + in_quotes(name) + " has no pathcl equivalent: ignored");
    }
  } else if (d == "WorldBegin") {
    require_options_block(p, t);
    p.in_world = true;
    gs.ctm = glm::dmat4(1.0);
    gs.start_transform_active = true;
    p.coordinate_systems["world"] = gs.ctm;
  } else if (d == "WorldEnd") {
    require_world_block(p, t);  // pbrt-v3's end of the scene: nothing to do
  } else if (d == "AttributeBegin" || d == "TransformBegin") {
    // pbrt-v4 reads pbrt-v3's TransformBegin/End as AttributeBegin/End.
    require_world_block(p, t);
    attribute_begin(p, 'a', at);
  } else if (d == "AttributeEnd" || d == "TransformEnd") {
    require_world_block(p, t);
    attribute_end(p, 'a', t);
  } else if (d == "Attribute") {
    require_world_block(p, t);
    std::string target = required_string(p, t, "shape, light, material, medium or texture");
    std::vector<Param> params = parse_params(p, "Attribute " + in_quotes(target));
    for (Param& prm : params) prm.from_attribute = true;
    std::vector<Param>* list = target == "shape"      ? &gs.shape_attributes
                               : target == "light"    ? &gs.light_attributes
                               : target == "material" ? &gs.material_attributes
                               : target == "medium"   ? &gs.medium_attributes
                               : target == "texture"  ? &gs.texture_attributes
                                                      : nullptr;
    if (!list)
      fail(at, "Attribute " + in_quotes(target) + ": expected \"shape\", \"light\", \"material\", \"medium\" or \"texture\"");
    list->insert(list->end(), params.begin(), params.end());
  } else if (d == "Material") {
    require_world_block(p, t);
    Entity e = parse_entity(p, t, gs.material_attributes);
    check_material_type(p.messages, e);
    gs.material = int(p.scene.materials.size());
    gs.named_material.clear();
    p.scene.materials.push_back({std::move(e), ""});
  } else if (d == "MakeNamedMaterial") {
    require_world_block(p, t);
    Entity e;
    e.directive = d;
    e.place = at;
    std::string name = required_string(p, t, "a material name");
    e.params = with_defaults(parse_params(p, "MakeNamedMaterial " + in_quotes(name)), gs.material_attributes);
    if (p.scene.named_materials.count(name))
      fail(at, "MakeNamedMaterial " + in_quotes(name) + ": the name is taken (first at " +
                   p.scene.materials[p.scene.named_materials[name]].entity.place.str() + ")");
    const Param* type = lookup(e.params, "MakeNamedMaterial " + in_quotes(name), "type", {"string"});
    if (!type) fail(at, "MakeNamedMaterial " + in_quotes(name) + " has no \"string type\" (the material type)");
    e.type = one_value(type)->strings[0];
    check_material_type(p.messages, e);
    p.scene.named_materials[name] = int(p.scene.materials.size());
    p.scene.materials.push_back({std::move(e), name});
  } else if (d == "NamedMaterial") {
    require_world_block(p, t);
    gs.named_material = required_string(p, t, "a material name");
    gs.named_material_place = at;
    gs.material = -1;
  } else if (d == "Texture") {
    require_world_block(p, t);
    TextureEntity tex;
    tex.name = required_string(p, t, "a texture name");
    std::string kind = required_string(p, t, "the texture type (\"spectrum\" or \"float\")");
    if (kind != "spectrum" && kind != "float" && kind != "color")
      fail(at, "Texture " + in_quotes(tex.name) + ": unknown texture type " + in_quotes(kind) + " (expected \"spectrum\" or \"float\")");
    tex.spectrum = kind != "float";
    tex.entity.directive = "Texture " + in_quotes(tex.name);
    tex.entity.place = at;
    tex.entity.type = required_string(p, t, "the texture class");
    tex.entity.params = with_defaults(parse_params(p, tex.entity.directive), gs.texture_attributes);
    check_type(tex.entity, {"imagemap", "constant", "scale", "mix", "directionmix", "checkerboard", "dots", "fbm",
                            "wrinkled", "windy", "marble", "ptex", "bilerp"},
               "texture class");
    auto& textures = tex.spectrum ? p.scene.spectrum_textures : p.scene.float_textures;
    if (textures.count(tex.name))
      fail(at, "Texture " + in_quotes(tex.name) + " is defined twice (first at " + textures.at(tex.name).entity.place.str() + ")");
    textures[tex.name] = std::move(tex);
  } else if (d == "LightSource") {
    require_world_block(p, t);
    Entity e = parse_entity(p, t, gs.light_attributes);
    check_type(e, {"point", "spot", "goniometric", "projection", "distant", "infinite"}, "light");
    p.scene.lights.push_back({std::move(e), gs.ctm, gs.outside_medium});
  } else if (d == "AreaLightSource") {
    require_world_block(p, t);
    Entity e = parse_entity(p, t, gs.light_attributes);
    check_type(e, {"diffuse"}, "area light");
    gs.area_light = std::move(e);
  } else if (d == "Shape") {
    require_world_block(p, t);
    add_shape(p, parse_entity(p, t, gs.shape_attributes));
  } else if (d == "ObjectBegin") {
    require_world_block(p, t);
    std::string name = required_string(p, t, "an object name");
    if (!p.object.empty()) fail(at, "ObjectBegin inside the definition of object " + in_quotes(p.object));
    if (p.scene.object_places.count(name))
      fail(at, "ObjectBegin " + in_quotes(name) + ": the object is defined twice (first at " +
                   p.scene.object_places[name].str() + ")");
    attribute_begin(p, 'o', at);
    p.object = name;
    p.scene.object_places[name] = at;
    p.scene.objects[name];
  } else if (d == "ObjectEnd") {
    require_world_block(p, t);
    if (p.object.empty()) fail(at, "ObjectEnd without ObjectBegin");
    attribute_end(p, 'o', t);
    p.object.clear();
  } else if (d == "ObjectInstance") {
    require_world_block(p, t);
    std::string name = required_string(p, t, "an object name");
    if (!p.object.empty()) fail(at, "ObjectInstance inside the definition of object " + in_quotes(p.object));
    p.scene.world.push_back({-1, int(p.scene.instance_uses.size())});
    p.scene.instance_uses.push_back({name, gs.ctm, at});
  } else if (d == "Include" || d == "Import") {
    include_file(p, t, d == "Import");
  } else if (d == "MakeNamedMedium") {
    std::string name = required_string(p, t, "a medium name");
    parse_params(p, "MakeNamedMedium " + in_quotes(name));
    if (p.scene.media.count(name))
      fail(at, "MakeNamedMedium " + in_quotes(name) + " is defined twice (first at " + p.scene.media[name].str() + ")");
    p.scene.media[name] = at;
  } else if (d == "MediumInterface") {
    gs.inside_medium = required_string(p, t, "a medium name");
    gs.outside_medium = gs.inside_medium;
    std::optional<Token> second = next_token(p);
    if (second && second->quoted)
      gs.outside_medium = second->text;
    else
      p.pushed_back = second;
    gs.medium_place = at;
  } else {
    fail(at, "unknown directive " + in_quotes(d));
  }
}

Scene parse_scene(Messages& messages, const std::string& path, const std::string& text) {
  Parser p{messages};
  p.main_dir = fs::path(path).parent_path();
  MaterialEntity fallback;
  fallback.entity = {"Material", "diffuse", Place{path, 0, p.main_dir}, {}};
  p.scene.materials.push_back(fallback);
  open_file(p, text, path, p.main_dir, false, Place{path, 0, p.main_dir});
  while (std::optional<Token> t = next_directive(p)) parse_directive(p, *t);
  if (!p.object.empty()) fail(p.scene.object_places[p.object], "ObjectBegin " + in_quotes(p.object) + " without ObjectEnd");
  if (!p.saved_states.empty()) fail(p.saved_kinds.back().second, "AttributeBegin without AttributeEnd");
  if (!p.in_world) throw SceneError(path + ": the file ends before WorldBegin (a pbrt scene needs a world block)");
  return std::move(p.scene);
}

// ---------------------------------------------------------------------------------------------------------
// Translation: the pathcl scene, its origins and warnings.

struct MaterialOut {
  std::string name;  // its name in the pathcl scene ("" until translated)
  bool interface = false;
  bool textured = false;
  bool dielectric = false;
  json material;
};

struct Translator {
  Translator(const Scene& s, Messages& m, const std::string& path)
      : scene(s), messages(m), main_dir(fs::path(path).parent_path()), main_file(path) {}
  const Scene& scene;
  Messages& messages;
  fs::path main_dir;
  std::string main_file;
  json shapes = json::array(), lights = json::array(), materials = json::object();
  std::vector<std::pair<std::string, std::string>> origins;
  std::map<int, MaterialOut> translated;  // by index into scene.materials
  std::set<std::string> names;            // taken material names
  int environment = -1;                   // index into lights of the environment light
};

void warn(Translator& t, const Place& at, const std::string& what) { warn(t.messages, at, what); }

// A material name not yet taken.
std::string unique_name(Translator& t, const std::string& wanted) {
  std::string name = wanted;
  for (int i = 2; t.names.count(name); ++i) name = wanted + " #" + std::to_string(i);
  t.names.insert(name);
  return name;
}

double luminance(glm::dvec3 c) { return 0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z; }

// ----- Spectra

enum class SpectrumUse { reflectance, emission, unbounded };

// Sellmeier coefficients (B1, B2, B3, C1, C2, C3; C in square micrometres) of the glasses behind pbrt-v4's
// named spectra glass-BK7, ..., glass-F11 (tabulated there as N-BK7, N-BAF10, N-FK51A, N-LASF9, SF5, SF10 and
// SF11), from the SCHOTT optical glass data sheets as refractiveindex.info lists them. They reproduce the
// catalogue's n_d at 587.56 nm (1.51680, 1.67003, 1.48656, 1.85025, 1.67270, 1.72825, 1.78472).
struct Glass {
  const char* name;
  double b1, b2, b3, c1, c2, c3;
};
const Glass kGlasses[] = {
    {"glass-BK7", 1.03961212, 0.231792344, 1.01046945, 0.00600069867, 0.0200179144, 103.560653},
    {"glass-BAF10", 1.5851495, 0.143559385, 1.08521269, 0.00926681282, 0.0424489805, 105.613573},
    {"glass-FK51A", 0.971247817, 0.216901417, 0.904651666, 0.00472301995, 0.0153575612, 168.68133},
    {"glass-LASF9", 2.00029547, 0.298926886, 1.80691843, 0.0121426017, 0.0538736236, 156.530829},
    {"glass-F5", 1.52481889, 0.187085527, 1.42729015, 0.011254756, 0.0588995392, 129.141675},
    {"glass-F10", 1.62153902, 0.256287842, 1.64447552, 0.0122241457, 0.0595736775, 147.468793},
    {"glass-F11", 1.73759695, 0.313747346, 1.89878101, 0.013188707, 0.0623068142, 155.23629},
};

// The index of refraction at 550 nm, near the peak of the eye's sensitivity.
double sellmeier_eta_550(const Glass& g) {
  double l2 = 0.55 * 0.55;
  return std::sqrt(1 + g.b1 * l2 / (l2 - g.c1) + g.b2 * l2 / (l2 - g.c2) + g.b3 * l2 / (l2 - g.c3));
}

const Glass* named_glass(const std::string& name) {
  for (const Glass& g : kGlasses)
    if (name == g.name) return &g;
  return nullptr;
}

struct Samples {
  std::vector<double> wavelengths, values;
};

// A spectrum written as [wavelength value ...]: wavelengths strictly increasing (pbrt-v4's check).
Samples samples_of(const std::vector<double>& numbers, const Place& at, const std::string& what) {
  Samples s;
  for (size_t i = 0; i + 1 < numbers.size(); i += 2) {
    if (!s.wavelengths.empty() && numbers[i] <= s.wavelengths.back())
      fail(at, what + ": the wavelengths of a spectrum must increase (" + num(numbers[i]) + " follows " +
                   num(s.wavelengths.back()) + ")");
    s.wavelengths.push_back(numbers[i]);
    s.values.push_back(numbers[i + 1]);
  }
  if (s.wavelengths.empty()) fail(at, what + ": expected [wavelength value ...] pairs");
  return s;
}

// A spectrum file (pbrt-v4's PiecewiseLinearSpectrum::Read): wavelength value pairs, '#' comments.
Samples read_spectrum_file(Translator& t, const std::string& written, const Place& at, const std::string& what) {
  std::string path = resolve_path(t.messages, t.main_dir, written, at, what);
  std::istringstream text(read_file(openable(t.main_dir, path), at, what));
  std::vector<double> numbers;
  std::string line, word;
  while (std::getline(text, line)) {
    std::istringstream words(line.substr(0, line.find('#')));
    while (words >> word) {
      char* end = nullptr;
      double v = std::strtod(word.c_str(), &end);
      if (end != word.c_str() + word.size() || !std::isfinite(v))
        fail(at, what + ": " + in_quotes(written) + " is neither a named spectrum nor a spectrum file (" + in_quotes(word) +
                     " is not a number)");
      numbers.push_back(v);
    }
  }
  if (numbers.size() % 2) fail(at, what + ": the spectrum file " + in_quotes(written) + " has an odd count of numbers");
  return samples_of(numbers, at, what + " (" + written + ")");
}

double value_at(const Samples& s, double wavelength) {
  if (wavelength <= s.wavelengths.front()) return s.values.front();
  if (wavelength >= s.wavelengths.back()) return s.values.back();
  size_t i = std::upper_bound(s.wavelengths.begin(), s.wavelengths.end(), wavelength) - s.wavelengths.begin();
  double f = (wavelength - s.wavelengths[i - 1]) / (s.wavelengths[i] - s.wavelengths[i - 1]);
  return s.values[i - 1] + f * (s.values[i] - s.values[i - 1]);
}

glm::dvec3 sampled_colour(Translator& t, const Samples& s, SpectrumUse use, const Place& at, const std::string& what) {
  bool clamped = false;
  glm::dvec3 c = use == SpectrumUse::reflectance ? reflectance_spectrum_to_srgb(s.wavelengths, s.values, &clamped)
                                                 : emission_spectrum_to_srgb(s.wavelengths, s.values, &clamped);
  if (clamped)
    warn(t, at, what + ": the spectrum's sRGB colour lies outside " +
                    (use == SpectrumUse::reflectance ? std::string("[0, 1]: clamped into it")
                                                     : std::string("the sRGB gamut: negative values clamped to 0")));
  return c;
}

// A named spectrum of pbrt-v4 (util/spectrum.cpp) as a colour: the metals' eta and k (Mitsuba's tables of
// the same metals), D65 and illuminant A (a 2856 K blackbody).
glm::dvec3 named_colour(Translator& t, const std::string& name, SpectrumUse use, const Place& at, const std::string& what) {
  if (name.rfind("metal-", 0) == 0 && use == SpectrumUse::unbounded) {
    size_t dash = name.rfind('-');
    std::string metal = name.substr(6, dash == std::string::npos || dash < 6 ? std::string::npos : dash - 6);
    std::string part = dash == std::string::npos ? "" : name.substr(dash + 1);
    glm::dvec3 eta, k;
    if ((part == "eta" || part == "k") && named_conductor(metal, &eta, &k)) return part == "eta" ? eta : k;
  }
  if (use == SpectrumUse::emission && name == "stdillum-D65") return glm::dvec3(1);  // sRGB's white point
  if (use == SpectrumUse::emission && name == "stdillum-A") return normalized_blackbody_to_srgb(2856);
  if (named_glass(name)) fail(at, what + ": " + in_quotes(name) + " is an index of refraction, not a colour");
  static const std::vector<std::string> metals = {"Ag", "Al", "Au", "Cu", "CuZn", "MgO", "TiO2"};
  std::vector<std::string> names;
  if (use == SpectrumUse::unbounded)
    for (const std::string& m : metals) names.push_back("metal-" + m + "-eta, metal-" + m + "-k");
  if (use == SpectrumUse::emission) names = {"stdillum-D65", "stdillum-A"};
  return sampled_colour(t, read_spectrum_file(t, name, at, what + " (" + in_quotes(name) + " is no named spectrum pathcl knows" +
                                                                 (names.empty() ? "" : ": " + join(names)) + ", nor a file)"),
                        use, at, what);
}

// The colour of a spectrum-valued parameter (rgb, spectrum or blackbody) as linear sRGB.
glm::dvec3 colour_of(Translator& t, const Param& p, SpectrumUse use, const std::string& what) {
  std::string where = what + ": " + p.decl();
  if (p.type == "rgb") {
    one_value(&p);
    glm::dvec3 c(p.numbers[0], p.numbers[1], p.numbers[2]);
    if (c.x < 0 || c.y < 0 || c.z < 0) fail(p.place, where + " has a negative component");
    if (use == SpectrumUse::reflectance && (c.x > 1 || c.y > 1 || c.z > 1))
      fail(p.place, where + " has a component > 1 (a reflectance is at most 1)");
    return c;
  }
  if (p.type == "blackbody") {
    if (p.numbers.size() != 1 && p.numbers.size() != 2)
      fail(p.place, where + ": expected a temperature in kelvin");
    if (use != SpectrumUse::emission) fail(p.place, where + ": a blackbody is an emission spectrum, not a reflectance");
    if (!(p.numbers[0] > 0)) fail(p.place, where + ": expected a temperature > 0 kelvin");
    // pbrt-v3 wrote [kelvin scale].
    return normalized_blackbody_to_srgb(p.numbers[0]) * (p.numbers.size() == 2 ? p.numbers[1] : 1.0);
  }
  if (p.type == "spectrum" && !p.strings.empty()) {
    if (p.strings.size() != 1) fail(p.place, where + ": expected one spectrum name");
    return named_colour(t, p.strings[0], use, p.place, where);
  }
  return sampled_colour(t, samples_of(p.numbers, p.place, where), use, p.place, where);
}

const std::vector<std::string> kSpectrumTypes = {"rgb", "spectrum", "blackbody"};

// pbrt-v4 divides a light's spectrum by its luminance (SpectrumToPhotometric: "scale so that radiance is
// equivalent to 1 nit"); for an rgb value it divides by the colour space illuminant's luminance only, so that
// an rgb value is the light's colour as is. Without a value the light is the colour space's illuminant,
// D65, which is sRGB's white (1, 1, 1) by definition.
glm::dvec3 light_colour(Translator& t, const Param* p, const std::string& what) {
  if (!p) return glm::dvec3(1);
  glm::dvec3 c = colour_of(t, *p, SpectrumUse::emission, what);
  if (p->type == "rgb") return c;
  double y = luminance(c);
  if (!(y > 0)) fail(p->place, what + ": " + p->decl() + " has no luminance in sRGB (pbrt-v4 normalises a light's spectrum by it)");
  return c / y;
}

// An index of refraction: a number, a named glass (at 550 nm: dispersion is not rendered) or a spectrum (also
// at 550 nm).
double ior_of(Translator& t, const Params& ps, const std::string& what, const std::string& name, double fallback) {
  const Param* p = lookup(ps, what, name, {"float", "spectrum", "rgb"});
  if (!p) return fallback;
  if (p->type == "float") return one_value(p)->numbers[0];
  if (p->type == "rgb") fail(p->place, what + ": " + p->decl() + ": give the index of refraction as a float or a spectrum");
  if (!p->strings.empty()) {
    if (const Glass* g = named_glass(p->strings[0])) {
      double eta = sellmeier_eta_550(*g);
      warn(t, p->place, what + ": " + p->decl() + " " + in_quotes(g->name) + " is taken at 550 nm (eta = " + num(eta) +
                            "): dispersion is not rendered");
      return eta;
    }
    std::vector<std::string> glasses;
    for (const Glass& g : kGlasses) glasses.push_back(g.name);
    Samples s = read_spectrum_file(t, p->strings[0], p->place,
                                   what + ": " + p->decl() + " (" + in_quotes(p->strings[0]) +
                                       " is not a named glass: " + join(glasses) + ", nor a spectrum file)");
    double eta = value_at(s, 550);
    warn(t, p->place, what + ": " + p->decl() + " is taken at 550 nm (eta = " + num(eta) + "): dispersion is not rendered");
    return eta;
  }
  Samples s = samples_of(p->numbers, p->place, what + ": " + p->decl());
  double eta = value_at(s, 550);
  if (std::any_of(s.values.begin(), s.values.end(), [&](double v) { return v != s.values.front(); }))
    warn(t, p->place, what + ": " + p->decl() + " is taken at 550 nm (eta = " + num(eta) + "): dispersion is not rendered");
  return eta;
}

// ----- Textures

// A texture as a pathcl material value: an image ({"texture": FILE, "wrap": ...}) or a constant.
struct TextureOut {
  bool image = false;
  json texture;
  glm::dvec3 colour{0};  // a constant spectrum texture
  double value = 0;      // a constant float texture
};

TextureOut translate_texture(Translator& t, const TextureEntity& tex, SpectrumUse use, int depth);

TextureOut texture_named(Translator& t, const std::string& name, bool spectrum, SpectrumUse use, const Place& at,
                         const std::string& what, int depth = 0) {
  const auto& textures = spectrum ? t.scene.spectrum_textures : t.scene.float_textures;
  auto it = textures.find(name);
  if (it == textures.end())
    fail(at, what + ": no " + (spectrum ? "spectrum" : "float") + " texture " + in_quotes(name) +
                 (((spectrum ? t.scene.float_textures : t.scene.spectrum_textures).count(name))
                      ? std::string(" (there is a ") + (spectrum ? "float" : "spectrum") + " texture of that name)"
                      : std::string("")));
  if (depth > 16) fail(at, what + ": textures refer to each other in a cycle");
  return translate_texture(t, it->second, use, depth + 1);
}

// An imagemap texture as a pathcl texture: the file and its wrap mode, where pbrt's options have a pathcl
// equivalent.
json image_texture(Translator& t, const TextureEntity& tex) {
  const Params& ps = tex.entity.params;
  const std::string what = tex.entity.directive + " (imagemap)";
  const Place& at = tex.entity.place;
  std::string written = get_string(ps, what, "filename", "");
  if (written.empty()) fail(at, what + " has no \"string filename\"");
  std::string file = resolve_path(t.messages, t.main_dir, written, at, what);
  std::string wrap = get_string(ps, what, "wrap", "repeat");
  if (wrap != "repeat" && wrap != "clamp")
    fail(at, what + ": wrap " + in_quotes(wrap) + " is not supported (pathcl's textures wrap as repeat, clamp or mirror)");
  if (double scale = get_float(ps, what, "scale", 1); scale != 1)
    fail(at, what + ": scale " + num(scale) + " is not supported (pathcl's image textures take no factor)");
  if (get_bool(ps, what, "invert", false)) fail(at, what + ": invert is not supported");
  std::string mapping = get_string(ps, what, "mapping", "uv");
  if (mapping != "uv") fail(at, what + ": mapping " + in_quotes(mapping) + " is not supported (pathcl maps images by uv)");
  double su = get_float(ps, what, "uscale", 1), sv = get_float(ps, what, "vscale", 1);
  double du = get_float(ps, what, "udelta", 0), dv = get_float(ps, what, "vdelta", 0);
  if (su != 1 || sv != 1 || du != 0 || dv != 0)
    fail(at, what + ": uscale, vscale, udelta and vdelta are not supported (pathcl maps the mesh's uv as is)");
  std::string filter = get_string(ps, what, "filter", "bilinear");
  get_float(ps, what, "maxanisotropy", 8);
  if (filter != "bilinear") warn(t, at, what + ": filter " + in_quotes(filter) + ": pathcl looks images up bilinearly");
  // pbrt-v4 decodes 8-bit images by "encoding", sRGB by default for PNG only; pathcl decodes every 8-bit
  // image as sRGB (floating-point images are linear in both).
  const std::string ext = lower_extension(written);
  bool eight_bit = ext == ".png" || ext == ".jpg" || ext == ".jpeg" || ext == ".tga" || ext == ".bmp";
  std::string encoding = get_string(ps, what, "encoding", ext == ".png" ? "sRGB" : "linear");
  if (eight_bit && encoding != "sRGB")
    warn(t, at, what + ": pbrt-v4 decodes " + in_quotes(written) + " with encoding " + in_quotes(encoding) +
                    ", pathcl decodes 8-bit images as sRGB: its colours differ");
  warn_unused(t.messages, ps, what);
  return {{"texture", file}, {"wrap", wrap}};
}

// pbrt-v4's 2D checkerboard: tex1 where floor(s) + floor(t) is even, tex2 elsewhere, (s, t) = (uscale u +
// udelta, vscale v + vdelta). pathcl's checkerboard is color0 where floor(x) + floor(y) is even with
// x = tiles_u u + offset_u and y = tiles_v (1 - v) + offset_v: the same parity for every v when offset_v =
// 1 - vscale - vdelta (mod 2), as floor(c - w) = c - 1 - floor(w) for an integer c and a w that is not one.
json checkerboard_texture(Translator& t, const TextureEntity& tex, SpectrumUse use, int depth) {
  const Params& ps = tex.entity.params;
  const std::string what = tex.entity.directive + " (checkerboard)";
  const Place& at = tex.entity.place;
  if (int dimension = get_int(ps, what, "dimension", 2); dimension != 2)
    fail(at, what + ": a " + std::to_string(dimension) + "D checkerboard is not supported (pathcl's is 2D, over uv)");
  std::string mapping = get_string(ps, what, "mapping", "uv");
  if (mapping != "uv") fail(at, what + ": mapping " + in_quotes(mapping) + " is not supported (pathcl maps by uv)");
  double su = get_float(ps, what, "uscale", 1), sv = get_float(ps, what, "vscale", 1);
  double du = get_float(ps, what, "udelta", 0), dv = get_float(ps, what, "vdelta", 0);
  if (!(su > 0 && sv > 0))
    fail(at, what + ": uscale and vscale must be > 0 for pathcl's checkerboard (got " + num(su) + ", " + num(sv) + ")");
  // Each checker's colour: a constant (rgb, spectrum, float) or a constant texture; pbrt-v4's defaults 1 and 0.
  auto colour = [&](const std::string& name, double fallback) {
    const Param* p = lookup(ps, what, name,
                            tex.spectrum ? std::vector<std::string>{"texture", "rgb", "spectrum", "blackbody"}
                                         : std::vector<std::string>{"texture", "float"});
    if (!p) return glm::dvec3(fallback);
    if (p->type == "texture") {
      TextureOut o = texture_named(t, one_value(p)->strings[0], tex.spectrum, use, p->place, what, depth);
      if (o.image) fail(p->place, what + ": " + p->decl() + ": a checker of a varying texture is not supported");
      return tex.spectrum ? o.colour : glm::dvec3(o.value);
    }
    if (p->type == "float") return glm::dvec3(one_value(p)->numbers[0]);
    return colour_of(t, *p, use, what);
  };
  const glm::dvec3 tex1 = colour("tex1", 1), tex2 = colour("tex2", 0);
  warn(t, at, what + ": pbrt-v4 filters the checkerboard over each ray's footprint, pathcl evaluates it at the point: "
                     "the same image once the pixels are integrated, its edges less blurred");
  warn_unused(t.messages, ps, what);
  const double offset_v = std::fmod(std::fmod(1 - sv - dv, 2.0) + 2.0, 2.0);
  return {{"checkerboard",
           {{"color0", vec_json(tex1)}, {"color1", vec_json(tex2)}, {"tiles", json::array({su, sv})},
            {"offset", json::array({std::fmod(std::fmod(du, 2.0) + 2.0, 2.0), offset_v})}}}};
}

TextureOut translate_texture(Translator& t, const TextureEntity& tex, SpectrumUse use, int depth) {
  const Params& ps = tex.entity.params;
  const std::string& kind = tex.entity.type;
  const std::string what = tex.entity.directive + " (" + kind + ")";
  TextureOut out;
  if (kind == "imagemap") {
    out.image = true;
    out.texture = image_texture(t, tex);
    return out;
  }
  if (kind == "constant") {
    if (tex.spectrum) {
      const Param* p = lookup(ps, what, "value", kSpectrumTypes);
      out.colour = p ? colour_of(t, *p, use, what) : glm::dvec3(1);
    } else {
      out.value = get_float(ps, what, "value", 1);
    }
    warn_unused(t.messages, ps, what);
    return out;
  }
  if (kind == "scale") {
    // tex times scale: an image times 1, or constants.
    auto operand = [&](const std::string& name, bool spectrum) {
      const Param* p = lookup(ps, what, name, spectrum ? std::vector<std::string>{"texture", "rgb", "spectrum", "blackbody"}
                                                       : std::vector<std::string>{"texture", "float"});
      TextureOut o;
      o.colour = glm::dvec3(1);
      o.value = 1;
      if (!p) return o;
      if (p->type == "texture") return texture_named(t, one_value(p)->strings[0], spectrum, use, p->place, what, depth);
      if (p->type == "float") o.value = one_value(p)->numbers[0];
      else o.colour = colour_of(t, *p, use, what);
      return o;
    };
    TextureOut a = operand("tex", tex.spectrum), s = operand("scale", false);
    warn_unused(t.messages, ps, what);
    if (s.image) fail(tex.entity.place, what + ": an image as the scale factor is not supported");
    if (a.image) {
      if (s.value != 1) fail(tex.entity.place, what + ": an image times " + num(s.value) + " is not supported (pathcl's image textures take no factor)");
      return a;
    }
    out.colour = a.colour * s.value;
    out.value = a.value * s.value;
    return out;
  }
  if (kind == "checkerboard") {
    out.image = true;
    out.texture = checkerboard_texture(t, tex, use, depth);
    return out;
  }
  fail(tex.entity.place, what + ": texture class " + in_quotes(kind) + " is not supported (supported: imagemap, constant, "
                         "checkerboard, and scale of an image by 1 or of constants)");
}

// A material colour (a reflectance): rgb, spectrum or a texture; json [r, g, b] or {"texture": ...}.
json albedo_of(Translator& t, const Params& ps, const std::string& what, const std::string& name, glm::dvec3 fallback,
               bool* textured) {
  const Param* p = lookup(ps, what, name, {"rgb", "spectrum", "blackbody", "texture"});
  if (!p) return vec_json(fallback);
  if (p->type != "texture") return vec_json(colour_of(t, *p, SpectrumUse::reflectance, what));
  TextureOut tex = texture_named(t, one_value(p)->strings[0], true, SpectrumUse::reflectance, p->place, what + ": " + p->decl());
  if (!tex.image) {
    if (tex.colour.x > 1 || tex.colour.y > 1 || tex.colour.z > 1)
      fail(p->place, what + ": " + p->decl() + " is a reflectance above 1");
    return vec_json(tex.colour);
  }
  *textured = true;
  return tex.texture;
}

// A number that may be given as a constant float texture (roughness).
double float_of(Translator& t, const Param* p, const std::string& what) {
  if (p->type == "float") return one_value(p)->numbers[0];
  TextureOut tex = texture_named(t, one_value(p)->strings[0], false, SpectrumUse::reflectance, p->place, what + ": " + p->decl());
  if (tex.image) fail(p->place, what + ": " + p->decl() + ": a texture that varies is not supported here (pathcl takes one number)");
  return tex.value;
}

// ----- Materials

// pbrt-v4's microfacet alpha of a material (materials.cpp): uroughness and vroughness, else roughness (0),
// through TrowbridgeReitzDistribution::RoughnessToAlpha (sqrt) unless remaproughness is false. pathcl is
// isotropic: two different alphas become their geometric mean, with a warning.
double alpha_of(Translator& t, const Params& ps, const std::string& what) {
  const std::vector<std::string> types = {"float", "texture"};
  const Param* r = lookup(ps, what, "roughness", types);
  const Param* u = lookup(ps, what, "uroughness", types);
  const Param* v = lookup(ps, what, "vroughness", types);
  double rough = r ? float_of(t, r, what) : 0;
  double ur = u ? float_of(t, u, what) : rough, vr = v ? float_of(t, v, what) : rough;
  bool remap = get_bool(ps, what, "remaproughness", true);
  auto alpha = [&](double x) { return remap ? std::sqrt(std::max(0.0, x)) : std::max(0.0, x); };
  double au = alpha(ur), av = alpha(vr);
  if (au != av) {
    warn(t, (u ? u : v)->place, what + ": anisotropic roughness (alpha " + num(au) + " along u, " + num(av) +
                                    " along v): pathcl's microfacets are isotropic, alpha " + num(std::sqrt(au * av)) +
                                    " (their geometric mean) is used");
    return std::sqrt(au * av);
  }
  return au;
}

// pbrt-v4 renders alpha below 1e-3 as perfectly smooth (TrowbridgeReitzDistribution::EffectivelySmooth).
bool effectively_smooth(double alpha) { return alpha < 1e-3; }

// pathcl's roughness is sqrt(alpha) (alpha = roughness^2), at most 1.
double pathcl_roughness(Translator& t, double alpha, const Place& at, const std::string& what) {
  double r = std::sqrt(alpha);
  if (r > 1) {
    warn(t, at, what + ": roughness alpha " + num(alpha) + " is beyond pathcl's largest (1): 1 is used");
    return 1;
  }
  return std::max(r, 0.01);
}

void drop_surface_detail(Translator& t, const Params& ps, const std::string& what, const Place& at) {
  if (const Param* n = lookup(ps, what, "normalmap", {"string"}))
    warn(t, n->place, what + ": normal map " + in_quotes(one_value(n)->strings[0]) + " dropped (pathcl has no normal mapping)");
  if (const Param* d = lookup(ps, what, "displacement", {"float", "texture"}))
    warn(t, d->place, what + ": displacement dropped (pathcl has no bump mapping)");
}

json conductor(Translator& t, const Params& ps, const std::string& what, const Place& at) {
  const Param* reflectance = lookup(ps, what, "reflectance", {"rgb", "spectrum", "blackbody", "texture"});
  const Param* eta = lookup(ps, what, "eta", {"rgb", "spectrum", "texture", "float"});
  const Param* k = lookup(ps, what, "k", {"rgb", "spectrum", "texture", "float"});
  if (reflectance && (eta || k)) fail(at, what + ": give either \"reflectance\" or \"eta\" and \"k\", not both");
  double alpha = alpha_of(t, ps, what);
  bool smooth = effectively_smooth(alpha);
  if (reflectance) {
    bool textured = false;
    json r = albedo_of(t, ps, what, "reflectance", glm::dvec3(0), &textured);
    if (textured) fail(reflectance->place, what + ": a textured conductor reflectance is not supported (pathcl's metals take one colour)");
    if (smooth) {
      // pbrt-v4's conductor of a reflectance r: eta 1, k = 2 sqrt(r / (1 - r)) (r at most 0.9999), as pathcl's
      // rough_conductor "specular"; smooth, pathcl's mirror with that eta and k.
      glm::dvec3 k;
      for (int c = 0; c < 3; ++c) {
        double rc = std::min(r[c].get<double>(), 0.9999);
        k[c] = 2 * std::sqrt(rc / (1 - rc));
      }
      return {{"type", "mirror"}, {"eta", vec_json(glm::dvec3(1))}, {"k", vec_json(k)}};
    }
    return {{"type", "rough_conductor"}, {"specular", r}, {"roughness", pathcl_roughness(t, alpha, at, what)}};
  }
  auto value = [&](const Param* p, const char* fallback_name, bool want_eta) -> glm::dvec3 {
    if (!p) {
      glm::dvec3 e, kk;
      if (!named_conductor("Cu", &e, &kk))
        fail(at, what + ": pbrt-v4's default conductor (" + fallback_name + ", copper) is not available (pathcl's named metals: " +
                     named_conductor_list() + ")");
      return want_eta ? e : kk;
    }
    if (p->type == "float") return glm::dvec3(one_value(p)->numbers[0]);
    if (p->type == "texture") {
      TextureOut tex = texture_named(t, one_value(p)->strings[0], true, SpectrumUse::unbounded, p->place, what + ": " + p->decl());
      if (tex.image) fail(p->place, what + ": " + p->decl() + ": an image for eta or k is not supported (pathcl's metals take one colour)");
      return tex.colour;
    }
    return colour_of(t, *p, SpectrumUse::unbounded, what);
  };
  glm::dvec3 e = value(eta, "metal-Cu-eta", true), kk = value(k, "metal-Cu-k", false);
  if (smooth) return {{"type", "mirror"}, {"eta", vec_json(e)}, {"k", vec_json(kk)}};
  return {{"type", "rough_conductor"}, {"eta", vec_json(e)}, {"k", vec_json(kk)},
          {"roughness", pathcl_roughness(t, alpha, at, what)}};
}

const std::vector<std::string> kSupportedMaterials = {"diffuse", "dielectric", "thindielectric", "conductor", "coateddiffuse",
                                                      "interface"};

MaterialOut translate_material(Translator& t, const MaterialEntity& m) {
  const Params& ps = m.entity.params;
  const Place& at = m.entity.place;
  const std::string what = m.name.empty() ? m.entity.what()
                                          : "MakeNamedMaterial " + in_quotes(m.name) + " (" + m.entity.type + ")";
  MaterialOut out;
  const std::string& type = m.entity.type;
  if (type == "interface") {
    out.interface = true;
    warn_unused(t.messages, ps, what);
    return out;
  }
  if (type == "diffuse") {
    out.material = {{"type", "diffuse"}, {"reflectance", albedo_of(t, ps, what, "reflectance", glm::dvec3(0.5), &out.textured)}};
  } else if (type == "dielectric") {
    double eta = ior_of(t, ps, what, "eta", 1.5);
    double alpha = alpha_of(t, ps, what);
    if (!effectively_smooth(alpha))
      warn(t, at, what + ": rough glass (alpha " + num(alpha) + ") is rendered smooth (pathcl's dielectric is smooth)");
    out.material = {{"type", "dielectric"}, {"ior", eta}};
    out.dielectric = true;
  } else if (type == "thindielectric") {
    out.material = {{"type", "thin_dielectric"}, {"ior", ior_of(t, ps, what, "eta", 1.5)}};
  } else if (type == "conductor") {
    out.material = conductor(t, ps, what, at);
  } else if (type == "coateddiffuse") {
    json diffuse = albedo_of(t, ps, what, "reflectance", glm::dvec3(0.5), &out.textured);
    double eta = ior_of(t, ps, what, "eta", 1.5);
    double alpha = alpha_of(t, ps, what);
    get_float(ps, what, "thickness", 0.01);
    get_int(ps, what, "maxdepth", 10);
    get_int(ps, what, "nsamples", 1);
    get_float(ps, what, "g", 0);
    bool albedo_given = false;
    json albedo = albedo_of(t, ps, what, "albedo", glm::dvec3(0), &albedo_given);
    std::string medium = albedo_given || albedo != vec_json(glm::dvec3(0)) ? " and its coat's albedo dropped" : "";
    warn(t, at, what + " is rendered as pathcl's plastic (a Lambertian base under a Fresnel coat) whose light reflected "
                       "inside the coat is lost, where pbrt-v4 simulates the layers (thickness, maxdepth, nsamples" +
                       std::string(medium.empty() ? "" : ", albedo, g") + "): it is somewhat darker" + medium);
    out.material = {{"type", "plastic"}, {"diffuse", diffuse}, {"ior", eta},
                    {"roughness", effectively_smooth(alpha) ? 0.0 : pathcl_roughness(t, alpha, at, what)}};
  } else {
    fail(at, what + ": Material " + in_quotes(type) + " is not supported (supported: " + join(kSupportedMaterials) + ")");
  }
  drop_surface_detail(t, ps, what, at);
  if (!m.name.empty()) lookup(ps, what, "type", {"string"});
  warn_unused(t.messages, ps, what);
  return out;
}

// The material of a shape, translated once and named in the pathcl scene.
const MaterialOut& material_of(Translator& t, const ShapeEntity& s) {
  int index = s.material;
  if (!s.named_material.empty()) {
    auto it = t.scene.named_materials.find(s.named_material);
    if (it == t.scene.named_materials.end())
      fail(s.named_material_place, "NamedMaterial " + in_quotes(s.named_material) + ": no MakeNamedMaterial defines it");
    index = it->second;
  }
  auto found = t.translated.find(index);
  if (found != t.translated.end()) return found->second;
  const MaterialEntity& m = t.scene.materials[index];
  MaterialOut out = translate_material(t, m);
  if (!out.interface) {
    if (index == 0)
      out.name = unique_name(t, "default");
    else if (!m.name.empty())
      out.name = m.name;  // reserved for it in translate_scene
    else
      out.name = unique_name(t, m.entity.type + "@" + fs::path(m.entity.place.file).filename().string() + ":" +
                                     std::to_string(m.entity.place.line));
    t.materials[out.name] = out.material;
    t.origins.push_back({"materials." + out.name,
                         m.entity.place.line ? m.entity.place.str() + ": " + (m.name.empty() ? m.entity.what() : "MakeNamedMaterial " + in_quotes(m.name))
                                             : m.entity.place.file + ": pbrt-v4's default material"});
  }
  return t.translated[index] = std::move(out);
}

// The material with a shape's "alpha" as its opacity, a variant of the material named after it.
std::string material_with_opacity(Translator& t, const MaterialOut& m, const json& opacity, const std::string& label) {
  std::string wanted = m.name + " (alpha " + label + ")";
  if (!t.materials.contains(wanted)) {
    json material = m.material;
    material["opacity"] = opacity;
    t.names.insert(wanted);
    t.materials[wanted] = material;
    auto origin = std::find_if(t.origins.begin(), t.origins.end(), [&](auto& o) { return o.first == "materials." + m.name; });
    if (origin != t.origins.end()) t.origins.push_back({"materials." + wanted, origin->second});
  }
  return wanted;
}

// ----- Shapes

// An inline triangle mesh in object space, as pbrt-v4 makes it.
struct Mesh {
  std::vector<glm::dvec3> p;
  std::vector<glm::ivec3> triangles;
  std::vector<glm::dvec2> uv;      // one per position, or none
  std::vector<glm::dvec3> normal;  // one per position, or none
  std::vector<int> primitive;      // per triangle: the pbrt primitive (triangle, patch) it belongs to
  std::vector<double> area;        // per primitive: its area as pbrt-v4's Shape::Area() gives it
  bool smooth = false;             // pathcl generates shading normals
};

double triangle_area(glm::dvec3 a, glm::dvec3 b, glm::dvec3 c) { return 0.5 * glm::length(glm::cross(b - a, c - a)); }

// Indices: `per` a primitive, all within the positions; none given and exactly `per` positions is one primitive.
std::vector<int> primitive_indices(const Params& ps, const std::string& what, const Place& at, size_t positions, int per) {
  std::vector<int> indices = get_ints(ps, what, "indices");
  if (indices.empty()) {
    if (positions != size_t(per))
      fail(at, what + " needs \"integer indices\" (" + std::to_string(per) + " a primitive) unless it has exactly " +
                   std::to_string(per) + " positions");
    for (int i = 0; i < per; ++i) indices.push_back(i);
  }
  if (indices.size() % per)
    fail(at, what + ": " + std::to_string(indices.size()) + " indices are not a multiple of " + std::to_string(per));
  for (int i : indices)
    if (i < 0 || size_t(i) >= positions)
      fail(at, what + ": index " + std::to_string(i) + " is out of range (" + std::to_string(positions) + " positions)");
  return indices;
}

// P, uv and N of trianglemesh and bilinearmesh.
Mesh mesh_vertices(Translator& t, const Params& ps, const std::string& what, const Place& at) {
  Mesh m;
  m.p = get_vec3s(ps, what, "P", {"point3"});
  if (m.p.empty()) fail(at, what + " needs positions \"point3 P\"");
  m.uv = get_uvs(ps, what);
  if (!m.uv.empty() && m.uv.size() != m.p.size())
    fail(at, what + ": " + std::to_string(m.uv.size()) + " uvs for " + std::to_string(m.p.size()) + " positions (expected one each)");
  m.normal = get_vec3s(ps, what, "N", {"normal"});
  if (!m.normal.empty() && m.normal.size() != m.p.size())
    fail(at, what + ": " + std::to_string(m.normal.size()) + " normals for " + std::to_string(m.p.size()) + " positions (expected one each)");
  get_ints(ps, what, "faceIndices");  // face indices serve ptex textures only, which are refused
  return m;
}

// pbrt-v4's default texture coordinates where a mesh has none: (0,0), (1,0), (1,1) at a triangle's corners
// (Triangle::GetUVs) and the patch's corners (0,0), (1,0), (0,1), (1,1) (BilinearPatch). Each triangle gets
// its own vertices.
void give_default_uvs(Mesh& m, bool patches) {
  Mesh out;
  out.primitive = m.primitive;
  out.area = m.area;
  for (size_t i = 0; i < m.triangles.size(); ++i) {
    glm::ivec3 tri = m.triangles[i];
    bool second = patches && i % 2 == 1;
    glm::dvec2 uvs[3] = {{0, 0}, {1, 0}, {1, 1}};
    if (second) uvs[1] = {1, 1}, uvs[2] = {0, 1};
    int base = int(out.p.size());
    for (int k = 0; k < 3; ++k) {
      out.p.push_back(m.p[tri[k]]);
      out.uv.push_back(uvs[k]);
      if (!m.normal.empty()) out.normal.push_back(m.normal[tri[k]]);
    }
    out.triangles.push_back({base, base + 1, base + 2});
  }
  out.smooth = m.smooth;
  m = std::move(out);
}

Mesh triangle_mesh(Translator& t, const Params& ps, const std::string& what, const Place& at, const glm::dmat4& ctm) {
  Mesh m = mesh_vertices(t, ps, what, at);
  std::vector<int> indices = primitive_indices(ps, what, at, m.p.size(), 3);
  if (const Param* s = lookup(ps, what, "S", {"vector3"}))
    warn(t, s->place, what + ": the tangents \"S\" are dropped (pathcl derives its shading frames itself)");
  for (size_t i = 0; i < indices.size(); i += 3) {
    glm::ivec3 tri(indices[i], indices[i + 1], indices[i + 2]);
    m.triangles.push_back(tri);
    m.primitive.push_back(int(m.area.size()));
    // pbrt-v4 keeps triangles in render space: an emitter's "power" is spread over the transformed area.
    m.area.push_back(triangle_area(transform_point(ctm, m.p[tri.x]), transform_point(ctm, m.p[tri.y]), transform_point(ctm, m.p[tri.z])));
  }
  return m;
}

// A bilinear patch (p00, p10, p01, p11) = indices (0, 1, 2, 3) becomes the triangles (p00, p10, p11) and
// (p00, p11, p01), which wind like the patch's normal cross(dp/du, dp/dv); exact for planar patches.
Mesh bilinear_mesh(Translator& t, const Params& ps, const std::string& what, const Place& at, const glm::dmat4& ctm) {
  Mesh m = mesh_vertices(t, ps, what, at);
  std::vector<int> indices = primitive_indices(ps, what, at, m.p.size(), 4);
  if (const Param* f = lookup(ps, what, "emissionfilename", {"string"}))
    fail(f->place, what + ": emission from an image is not supported");
  int curved = 0;
  for (size_t i = 0; i < indices.size(); i += 4) {
    int v00 = indices[i], v10 = indices[i + 1], v01 = indices[i + 2], v11 = indices[i + 3];
    glm::dvec3 p00 = m.p[v00], p10 = m.p[v10], p01 = m.p[v01], p11 = m.p[v11];
    glm::dvec3 n = glm::cross(p10 - p00, p01 - p00);
    double size = std::max({glm::length(p10 - p00), glm::length(p01 - p00), glm::length(p11 - p00)});
    if (glm::length(n) > 0 && std::abs(glm::dot(glm::normalize(n), p11 - p00)) > 1e-6 * size) ++curved;
    int primitive = int(m.area.size());
    m.triangles.push_back({v00, v10, v11});
    m.triangles.push_back({v00, v11, v01});
    m.primitive.insert(m.primitive.end(), {primitive, primitive});
    glm::dvec3 w00 = transform_point(ctm, p00), w10 = transform_point(ctm, p10), w01 = transform_point(ctm, p01), w11 = transform_point(ctm, p11);
    m.area.push_back(triangle_area(w00, w10, w11) + triangle_area(w00, w11, w01));
  }
  if (curved)
    warn(t, at, what + ": " + std::to_string(curved) + " of its " + std::to_string(indices.size() / 4) +
                    " patches are not planar: each is rendered as two flat triangles");
  return m;
}

int segments_for(double phimax_degrees) { return std::max(3, int(std::ceil(128 * phimax_degrees / 360))); }

// A disk (pbrt-v4's Disk: at z = height, facing +z, radius to innerradius, phi up to phimax) as triangles.
// Two rings of n + 1 vertices each about z, interleaved (vertex 2i on the first ring, 2i + 1 on the second, at
// phi = phimax i / n), with uv (i / n, 0) and (i / n, 1): the strip a disk and a cylinder are made of.
void add_ring_strip(Mesh& m, int n, double phimax_degrees, double r0, double z0, double r1, double z1) {
  for (int i = 0; i <= n; ++i) {
    double phi = phimax_degrees * kPi / 180 * i / n, u = double(i) / n;
    m.p.push_back({r0 * std::cos(phi), r0 * std::sin(phi), z0});
    m.uv.push_back({u, 0});
    m.p.push_back({r1 * std::cos(phi), r1 * std::sin(phi), z1});
    m.uv.push_back({u, 1});
  }
}

Mesh disk_mesh(Translator& t, const Params& ps, const std::string& what, const Place& at) {
  double h = get_float(ps, what, "height", 0), r = get_float(ps, what, "radius", 1);
  double ri = get_float(ps, what, "innerradius", 0), phimax = std::clamp(get_float(ps, what, "phimax", 360), 0.0, 360.0);
  if (!(r > 0) || ri < 0 || ri >= r || phimax <= 0) fail(at, what + ": expected 0 <= innerradius < radius and phimax > 0");
  int n = segments_for(phimax);
  Mesh m;
  add_ring_strip(m, n, phimax, r, h, ri, h);  // the outer ring, then the inner
  for (int i = 0; i < n; ++i) {
    int o0 = 2 * i, i0 = 2 * i + 1, o1 = 2 * i + 2, i1 = 2 * i + 3;
    m.triangles.push_back({i0, o0, o1});
    if (ri > 0) m.triangles.push_back({i0, o1, i1});
  }
  m.primitive.assign(m.triangles.size(), 0);
  m.area = {0.5 * phimax * kPi / 180 * (r * r - ri * ri)};
  warn(t, at, what + " is tessellated into " + std::to_string(m.triangles.size()) + " triangles (pathcl has no analytic disk)");
  return m;
}

// A cylinder (pbrt-v4's Cylinder: about z from zmin to zmax, facing outwards) as smooth-shaded triangles.
Mesh cylinder_mesh(Translator& t, const Params& ps, const std::string& what, const Place& at) {
  double r = get_float(ps, what, "radius", 1), z0 = get_float(ps, what, "zmin", -1), z1 = get_float(ps, what, "zmax", 1);
  double phimax = std::clamp(get_float(ps, what, "phimax", 360), 0.0, 360.0);
  if (!(r > 0) || z0 == z1 || phimax <= 0) fail(at, what + ": expected radius > 0, zmin != zmax and phimax > 0");
  if (z0 > z1) std::swap(z0, z1);
  int n = segments_for(phimax);
  Mesh m;
  add_ring_strip(m, n, phimax, r, z0, r, z1);  // the bottom ring, then the top
  for (int i = 0; i < n; ++i) {
    int b0 = 2 * i, t0 = 2 * i + 1, b1 = 2 * i + 2, t1 = 2 * i + 3;
    m.triangles.push_back({b0, b1, t1});
    m.triangles.push_back({b0, t1, t0});
  }
  m.primitive.assign(m.triangles.size(), 0);
  m.area = {(z1 - z0) * r * phimax * kPi / 180};
  m.smooth = true;
  warn(t, at, what + " is tessellated into " + std::to_string(m.triangles.size()) +
                  " triangles with smooth shading normals (pathcl has no analytic cylinder)");
  return m;
}

// pbrt-v4's front side of a mesh triangle: cross(p1 - p0, p2 - p0) (its cross(dp02, dp12)), turned towards the
// shading normals where the mesh has them, and turned over by ReverseOrientation. pathcl's front side is
// cross(p1 - p0, p2 - p0), and both keep the object-space front under a mirroring transform, so a triangle
// is reversed where pbrt's front is its back.
void orient_like_pbrt(Mesh& m, bool reverse_orientation) {
  for (glm::ivec3& tri : m.triangles) {
    bool flip = reverse_orientation;
    if (!m.normal.empty()) {
      glm::dvec3 geometric = glm::cross(m.p[tri.y] - m.p[tri.x], m.p[tri.z] - m.p[tri.x]);
      glm::dvec3 shading = m.normal[tri.x] + m.normal[tri.y] + m.normal[tri.z];
      if (glm::dot(geometric, shading) < 0) flip = !flip;
    }
    if (flip) std::swap(tri.y, tri.z);
  }
}

// pathcl's inline triangles take no normals: a mesh whose normals are its faces' is exact without them;
// otherwise pathcl generates smooth ones (a 60 degree crease angle), with a warning.
void replace_normals(Translator& t, Mesh& m, const Place& at, const std::string& what) {
  if (m.normal.empty()) return;
  bool flat = true;
  for (const glm::ivec3& tri : m.triangles) {
    glm::dvec3 g = glm::cross(m.p[tri.y] - m.p[tri.x], m.p[tri.z] - m.p[tri.x]);
    if (glm::length(g) == 0) continue;
    g = glm::normalize(g);
    for (int k = 0; k < 3; ++k) {
      glm::dvec3 n = m.normal[tri[k]];
      if (glm::length(n) == 0 || std::abs(glm::dot(glm::normalize(n), g)) < std::cos(kPi / 180)) flat = false;
    }
  }
  if (!flat) {
    m.smooth = true;
    warn(t, at, what + ": its normals \"N\" are replaced by smooth normals that pathcl generates (\"smooth\": true, a "
                       "60 degree crease angle): pathcl's inline triangles take no normals");
  }
  m.normal.clear();
}

// The triangles shape of some of a mesh's triangles: all of them with the vertices as numbered, or a part
// with only the vertices it uses, renumbered.
json mesh_json(const Mesh& m, const std::vector<size_t>& triangles) {
  bool whole = triangles.size() == m.triangles.size();
  std::map<int, int> renumber;
  json positions = json::array(), indices = json::array(), uvs = json::array();
  auto add_vertex = [&](int v) {
    positions.push_back(vec_json(m.p[v]));
    if (!m.uv.empty()) uvs.push_back({m.uv[v].x, m.uv[v].y});
  };
  if (whole)
    for (size_t v = 0; v < m.p.size(); ++v) add_vertex(int(v));
  for (size_t i : triangles) {
    json tri = json::array();
    for (int k = 0; k < 3; ++k) {
      int v = m.triangles[i][k];
      // Unsigned, as JSON text reads back (pathcl's loader takes vertex indices as unsigned integers).
      if (whole) {
        tri.push_back(uint64_t(v));
        continue;
      }
      auto [it, added] = renumber.insert({v, int(renumber.size())});
      if (added) add_vertex(v);
      tri.push_back(uint64_t(it->second));
    }
    indices.push_back(tri);
  }
  json shape = {{"type", "triangles"}, {"positions", positions}, {"indices", indices}};
  if (!m.uv.empty()) shape["uvs"] = uvs;
  if (m.smooth) shape["smooth"] = true;
  return shape;
}

// A PLY file's header names vertex normals (nx): pbrt-v4 then takes a face's front side from them.
bool ply_has_normals(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::string line;
  for (int i = 0; i < 200 && std::getline(in, line); ++i) {
    if (line.rfind("end_header", 0) == 0) break;
    std::istringstream words(line);
    std::string a, b, c, d;
    words >> a >> b >> c >> d;
    if (a == "property" && (c == "nx" || d == "nx")) return true;
  }
  return false;
}

struct ShapeContext {
  const ShapeEntity& s;
  glm::dmat4 world_from_object;
  std::string origin;  // the source place of the pathcl shapes
  bool instanced = false;
};

// The area light of a shape: radiance, sides and pbrt-v4's "power" (spread over each primitive's area).
struct Emission {
  bool emits = false;
  glm::dvec3 radiance{0};
  bool two_sided = false;
  double power = -1;
  Place place;
  std::string what;
};

Emission emission_of(Translator& t, const ShapeContext& c) {
  Emission e;
  if (!c.s.area_light) return e;
  const Entity& light = *c.s.area_light;
  if (c.instanced) {
    warn(t, c.s.entity.place, c.s.entity.what() + " in an object definition: its AreaLightSource is ignored (pbrt-v4 "
                              "does not support area lights with object instancing either)");
    return e;
  }
  e.emits = true;
  e.place = light.place;
  e.what = light.what();
  const Params& ps = light.params;
  if (const Param* f = lookup(ps, e.what, "filename", {"string"}))
    fail(f->place, e.what + ": emission from an image is not supported");
  const Param* L = lookup(ps, e.what, "L", kSpectrumTypes);
  e.radiance = light_colour(t, L, e.what) * get_float(ps, e.what, "scale", 1);
  e.two_sided = get_bool(ps, e.what, "twosided", false);
  e.power = get_float(ps, e.what, "power", -1);
  warn_unused(t.messages, ps, e.what);
  return e;
}

// pbrt-v4 gives "power" to each primitive (each triangle, each patch) of an area light: radiance
// power / ((two-sided ? 2 : 1) pi area) times the spectrum (DiffuseAreaLight::Create).
glm::dvec3 radiance_for_power(const Emission& e, double area) {
  return e.radiance * (e.power / ((e.two_sided ? 2 : 1) * kPi * area));
}

void add_common_keys(json& shape, const std::string& material, const glm::dmat4& transform, const Emission& e,
                     glm::dvec3 radiance) {
  shape["material"] = material;
  if (!is_identity(transform)) shape["transform"] = {{"matrix", matrix_json(transform)}};
  if (e.emits) {
    shape["emission"] = vec_json(radiance);
    if (e.two_sided) shape["two_sided"] = true;
  }
}

void push_shape(Translator& t, json shape, const std::string& origin) {
  t.origins.push_back({"shapes[" + std::to_string(t.shapes.size()) + "]", origin});
  t.shapes.push_back(std::move(shape));
}

// A mesh as one triangles shape, or, where "power" gives its primitives different radiances, one per primitive.
void push_mesh(Translator& t, const ShapeContext& c, Mesh& m, const std::string& material, const Emission& e) {
  auto all = [&] {
    std::vector<size_t> v(m.triangles.size());
    for (size_t i = 0; i < v.size(); ++i) v[i] = i;
    return v;
  };
  bool equal_areas = std::all_of(m.area.begin(), m.area.end(), [&](double a) { return std::abs(a - m.area[0]) <= 1e-9 * m.area[0]; });
  if (!e.emits || e.power <= 0 || equal_areas) {
    json shape = mesh_json(m, all());
    glm::dvec3 radiance = e.emits && e.power > 0 ? radiance_for_power(e, m.area[0]) : e.radiance;
    add_common_keys(shape, material, c.world_from_object, e, radiance);
    push_shape(t, std::move(shape), c.origin);
    return;
  }
  warn(t, e.place, e.what + ": \"power\" is given to each of the " + std::to_string(m.area.size()) +
                       " primitives of the " + c.s.entity.what() + " at line " + std::to_string(c.s.entity.place.line) +
                       " (as pbrt-v4 does), whose areas differ: one pathcl shape each");
  std::vector<std::vector<size_t>> by_primitive(m.area.size());
  for (size_t i = 0; i < m.triangles.size(); ++i) by_primitive[m.primitive[i]].push_back(i);
  for (size_t k = 0; k < by_primitive.size(); ++k) {
    json shape = mesh_json(m, by_primitive[k]);
    add_common_keys(shape, material, c.world_from_object, e, radiance_for_power(e, m.area[k]));
    push_shape(t, std::move(shape), c.origin);
  }
}

void check_transform(const glm::dmat4& m, const Place& at, const std::string& what) {
  if (!is_affine(m)) fail(at, what + ": its transform is projective (the last row of the matrix is not 0 0 0 1)");
  if (glm::determinant(glm::dmat3(m)) == 0) fail(at, what + ": its transform is singular (a Scale by 0?)");
}

void translate_shape(Translator& t, const ShapeContext& c) {
  const ShapeEntity& s = c.s;
  const Params& ps = s.entity.params;
  const std::string what = s.entity.what();
  const Place& at = s.entity.place;
  const std::string& type = s.entity.type;
  check_transform(c.world_from_object, at, what);
  if (!s.inside_medium.empty() || !s.outside_medium.empty())
    fail(at, what + ": participating media are not supported (MediumInterface at " + s.medium_place.str() +
                 " puts this shape between media " + in_quotes(s.inside_medium) + " and " + in_quotes(s.outside_medium) + ")");
  if (type == "curve" || type == "loopsubdiv")
    fail(at, "Shape " + in_quotes(type) + " is not supported (supported: trianglemesh, plymesh, bilinearmesh, sphere, "
                                       "and disk and cylinder as triangles)");
  const MaterialOut& material = material_of(t, s);
  if (material.interface) {
    for (const Param& p : ps.list) p.used = true;
    warn(t, at, what + " has the \"interface\" material (no surface, a boundary between media): left out");
    return;
  }
  Emission e = emission_of(t, c);

  // "alpha": the material's opacity (a cut-out).
  std::string material_name = material.name;
  if (const Param* a = lookup(ps, what, "alpha", {"float", "texture"})) {
    json opacity;
    std::string label;
    if (a->type == "float") {
      opacity = std::clamp(one_value(a)->numbers[0], 0.0, 1.0);
      label = num(opacity.get<double>());
    } else {
      TextureOut tex = texture_named(t, one_value(a)->strings[0], false, SpectrumUse::reflectance, a->place, what + ": " + a->decl());
      if (tex.image) {
        opacity = tex.texture;
        label = in_quotes(a->strings[0]);
        warn(t, a->place, what + ": alpha texture " + in_quotes(a->strings[0]) + ": pbrt-v4 reads the image's first channel "
                              "(decoded as its encoding says), pathcl an 8-bit image's alpha channel where it has one that "
                              "is not opaque, else its red channel, linearly: the same for black-and-white masks");
      } else {
        opacity = std::clamp(tex.value, 0.0, 1.0);
        label = num(opacity.get<double>());
      }
    }
    bool cut = !opacity.is_number() || opacity.get<double>() < 1;
    if (cut && e.emits) {
      warn(t, a->place, what + ": alpha on an emitter is dropped (pathcl's emitters cannot be cut-outs)");
    } else if (cut) {
      if (type == "sphere" && !opacity.is_number())
        fail(a->place, what + ": an alpha texture on a sphere is not supported (pathcl's spheres take a constant opacity)");
      material_name = material_with_opacity(t, material, opacity, label);
    }
  }
  const json& chosen = t.materials[material_name];
  bool textured = material.textured || (chosen.contains("opacity") && chosen["opacity"].is_object());

  if (type == "sphere") {
    double r = get_float(ps, what, "radius", 1);
    double zmin = get_float(ps, what, "zmin", -r), zmax = get_float(ps, what, "zmax", r);
    double phimax = get_float(ps, what, "phimax", 360);
    if (zmin > -r || zmax < r || phimax < 360)
      fail(at, what + ": a partial sphere (zmin, zmax or phimax) is not supported (pathcl's spheres are whole)");
    if (!(r > 0)) fail(at, what + ": expected a radius > 0");
    if (!is_similarity(glm::dmat3(c.world_from_object)))
      fail(at, what + ": its transform scales unevenly or shears, which makes an ellipsoid (pathcl's spheres take "
                      "translation, rotation and uniform scale)");
    // pbrt's sphere has its pole on +z and u = phi / 2pi from +x towards +y; pathcl's has its pole on +y and
    // u from +x towards -z: rotating pathcl's frame onto pbrt's keeps textures where pbrt puts them.
    glm::dmat4 pole_to_z(glm::dvec4(1, 0, 0, 0), glm::dvec4(0, 0, 1, 0), glm::dvec4(0, -1, 0, 0), glm::dvec4(0, 0, 0, 1));
    if (glm::determinant(glm::dmat3(c.world_from_object)) < 0 && e.emits && !e.two_sided)
      warn(t, at, what + ": under a mirroring transform pbrt-v4 samples this one-sided emitter from outside but lets it "
                         "emit inwards when a ray hits it; pathcl emits outwards");
    json shape = {{"type", "sphere"}, {"radius", r}};
    if (s.reverse_orientation) shape["flip_normals"] = true;
    glm::dvec3 radiance = e.emits && e.power > 0 ? radiance_for_power(e, 4 * kPi * r * r) : e.radiance;
    add_common_keys(shape, material_name, c.world_from_object * pole_to_z, e, radiance);
    push_shape(t, std::move(shape), c.origin);
  } else if (type == "plymesh") {
    std::string written = get_string(ps, what, "filename", "");
    if (written.empty()) fail(at, what + " has no \"string filename\"");
    std::string file = resolve_path(t.messages, t.main_dir, written, at, what);
    if (const Param* d = lookup(ps, what, "displacement", {"texture", "float"}))
      fail(d->place, what + ": displacement is not supported");
    get_float(ps, what, "edgelength", 1);
    bool one_sided_emitter = e.emits && !e.two_sided;
    if (s.reverse_orientation && (one_sided_emitter || material.dielectric))
      fail(at, what + ": ReverseOrientation turns the file's faces over, which pathcl cannot do for a mesh file " +
                   (material.dielectric ? std::string("of glass (its inside would be its outside)") : std::string("that emits from one side")) +
                   " (write its faces the other way round, or make the light two-sided)");
    fs::path full = openable(t.main_dir, file);
    if (one_sided_emitter && ply_has_normals(full))
      warn(t, at, what + ": pbrt-v4 emits from the side its vertex normals face, pathcl from the side its faces wind "
                         "counter-clockwise: the same where the file's normals agree with its winding");
    if (e.emits && e.power > 0)
      fail(e.place, e.what + ": \"power\" on a plymesh is not supported (pathcl would need the file's triangle areas; give \"L\")");
    json shape = {{"type", "mesh"}, {"file", file}};
    add_common_keys(shape, material_name, c.world_from_object, e, e.radiance);
    push_shape(t, std::move(shape), c.origin);
  } else {
    Mesh m = type == "trianglemesh"   ? triangle_mesh(t, ps, what, at, c.world_from_object)
             : type == "bilinearmesh" ? bilinear_mesh(t, ps, what, at, c.world_from_object)
             : type == "disk"         ? disk_mesh(t, ps, what, at)
                                      : cylinder_mesh(t, ps, what, at);
    // pbrt's default uvs go with the corners as pbrt numbers them, so before any triangle is turned over.
    if (textured && m.uv.empty()) give_default_uvs(m, type == "bilinearmesh");
    orient_like_pbrt(m, s.reverse_orientation);
    replace_normals(t, m, at, what);
    push_mesh(t, c, m, material_name, e);
  }
  warn_unused(t.messages, ps, what);
}

// ----- Lights

// Where the light pushed as lights[index] came from ("scene.pbrt:12: LightSource \"infinite\"").
std::string origin_of(const Translator& t, int index) {
  const std::string key = "lights[" + std::to_string(index) + "]";
  for (const auto& [k, v] : t.origins)
    if (k == key) return v;
  return key;
}

// The rotation part of a light's CTM, which must be a rotation times a uniform scale (pbrt-v4 normalises
// the light-space direction, so a uniform scale and a translation change nothing); the nearest rotation
// (the polar factor, by Newton's iteration in double), so that the JSON holds an exact rotation.
glm::dmat3 light_rotation(const glm::dmat4& ctm, const Place& at, const std::string& what) {
  glm::dmat3 m(ctm);
  if (!is_similarity(m))
    fail(at, what + ": its transform scales unevenly or shears, which bends the image's directions (an environment "
                    "map takes a rotation only)");
  if (glm::determinant(m) < 0)
    fail(at, what + ": its transform mirrors, which would mirror the image (an environment map takes a rotation only)");
  glm::dmat3 r = m / std::cbrt(glm::determinant(m));
  for (int i = 0; i < 8; ++i) r = 0.5 * (r + glm::transpose(glm::inverse(r)));
  return r;
}

// pbrt-v4's image RGB colour space (Image::Read: an OpenEXR file's "chromaticities", looked up among the
// colour spaces pbrt knows with a relative tolerance of 1e-3; sRGB otherwise): sRGB only, as pathcl renders
// sRGB. A file that cannot be read here is left to the loader, which names the problem.
void check_image_colour_space(Translator& t, const fs::path& file, const Place& at, const std::string& what) {
  {
    std::ifstream in(file, std::ios::binary);
    char magic[4] = {};
    if (!in.read(magic, 4) || std::memcmp(magic, "\x76\x2f\x31\x01", 4) != 0) return;  // not OpenEXR: sRGB
  }
  Imf::Chromaticities c;
  try {
    Imf::InputFile exr(file.string().c_str());
    const auto* attribute = exr.header().findTypedAttribute<Imf::ChromaticitiesAttribute>("chromaticities");
    if (!attribute) return;
    c = attribute->value();
  } catch (const std::exception&) {
    return;
  }
  struct Space {
    const char* name;
    double r[2], g[2], b[2], w[2];
  };
  // pbrt-v4's RGBColorSpace::Init; the white points of D65 and ACES' D60 as pbrt computes them from the
  // illuminants' spectra (x, y to 4 digits, well within the 1e-3 relative tolerance).
  const Space spaces[] = {{"srgb", {0.64, 0.33}, {0.3, 0.6}, {0.15, 0.06}, {0.3127, 0.3290}},
                          {"dci-p3", {0.68, 0.32}, {0.265, 0.690}, {0.15, 0.06}, {0.3127, 0.3290}},
                          {"rec2020", {0.708, 0.292}, {0.170, 0.797}, {0.131, 0.046}, {0.3127, 0.3290}},
                          {"aces2065-1", {0.7347, 0.2653}, {0.0, 1.0}, {0.0001, -0.077}, {0.32168, 0.33767}}};
  auto close = [](float a, double b) { return a == b || std::abs((a - b) / b) < 1e-3; };
  auto same = [&](const Imath::V2f& p, const double q[2]) { return close(p.x, q[0]) && close(p.y, q[1]); };
  for (const Space& s : spaces) {
    if (!(same(c.red, s.r) && same(c.green, s.g) && same(c.blue, s.b) && same(c.white, s.w))) continue;
    if (std::string(s.name) == "srgb") return;
    fail(at, what + ": " + in_quotes(file.generic_string()) + " is in the " + s.name + " colour space (its chromaticities): "
             "pathcl renders sRGB and takes images in sRGB only");
  }
  warn(t, at, what + ": " + in_quotes(file.generic_string()) + ": its chromaticities are no colour space pbrt-v4 knows: "
                     "taken as sRGB, as pbrt-v4 does");
}

// An image light: pbrt-v4's ImageInfiniteLight, an equal-area octahedral square map (lights.cpp) looked up
// at the nearest texel (ImageLe), its directions in light space: the map's frame is the CTM's rotation.
// "illuminance" E scales the map so that pbrt's estimate of the upper hemisphere's illuminance,
// k = 2 pi / (w h) times the sum over texels whose centre lies above the horizon (light-space z > 0) of
// luminance x cos theta at the centre, becomes E: scale x E / k (pbrt-v4's formula as it is; it counts
// 2 pi, not 4 pi, per w h texels, so the map's true illuminance is then 2 E).
json image_environment(Translator& t, const LightEntity& l, const std::string& filename, double scale) {
  const Params& ps = l.entity.params;
  const std::string what = l.entity.what();
  const Place& at = l.entity.place;
  const Param* f = lookup(ps, what, "filename", {"string"});
  const std::string file = resolve_path(t.messages, t.main_dir, filename, f->place, what);
  const fs::path openable_file = openable(t.main_dir, file);
  check_image_colour_space(t, openable_file, f->place, what);
  json light = {{"type", "environment"}, {"file", file}, {"mapping", "equal_area"}, {"filter", "nearest"}};
  if (double e = get_float(ps, what, "illuminance", -1); e > 0) {
    TextureImage image;
    try {
      image = load_texture_image(openable_file.string());
    } catch (const SceneError& error) {
      fail(f->place, what + ": " + error.what());
    }
    if (image.width != image.height)
      fail(f->place, what + ": " + in_quotes(file) + " is " + std::to_string(image.width) + " x " +
                         std::to_string(image.height) + " texels, not square (pbrt-v4's environment maps are "
                         "equal-area octahedral squares)");
    // The Y row of sRGB's RGB-to-XYZ matrix, pbrt's RGBColorSpace::LuminanceVector.
    const glm::dvec3 y_row(0.2126390058715102, 0.7151686787677559, 0.0721923153607337);
    double sum = 0;
    for (uint32_t row = 0; row < image.height; ++row)
      for (uint32_t col = 0; col < image.width; ++col) {
        // pbrt-v4's EqualAreaSquareToSphere: z at the texel's centre (its sign and its value).
        double u = 2 * (col + 0.5) / image.width - 1, v = 2 * (row + 0.5) / image.height - 1;
        double signed_distance = 1 - (std::abs(u) + std::abs(v)), r = 1 - std::abs(signed_distance);
        double z = std::copysign(1 - r * r, signed_distance);
        if (z <= 0) continue;
        sum += glm::dot(glm::dvec3(texel_linear(image, size_t(row) * image.width + col)), y_row) * z;
      }
    double k = sum * 2 * kPi / (double(image.width) * image.height);
    if (!(k > 0))
      fail(at, what + ": \"illuminance\" " + num(e) + ": the image is black above the horizon (light-space z > 0), "
                      "which pbrt-v4 would divide by");
    scale *= e / k;
  }
  light["scale"] = scale;
  glm::dmat3 r = light_rotation(l.ctm, at, what);
  if (r != glm::dmat3(1.0)) light["transform"] = {{"matrix", matrix_json(glm::dmat4(r))}};
  return light;
}

void check_light_medium(const LightEntity& l) {
  if (!l.medium.empty())
    fail(l.entity.place, l.entity.what() + ": participating media are not supported (the light is in medium " +
                             in_quotes(l.medium) + ")");
}

void push_light(Translator& t, json light, const Place& at, const std::string& what) {
  t.origins.push_back({"lights[" + std::to_string(t.lights.size()) + "]", at.str() + ": " + what});
  t.lights.push_back(std::move(light));
}

void translate_light(Translator& t, const LightEntity& l) {
  const Params& ps = l.entity.params;
  const std::string what = l.entity.what();
  const Place& at = l.entity.place;
  const std::string& type = l.entity.type;
  check_light_medium(l);
  if (type == "goniometric" || type == "projection")
    fail(at, "LightSource " + in_quotes(type) + " is not supported (supported: point, spot, distant, infinite)");
  check_transform(l.ctm, at, what);
  double scale = get_float(ps, what, "scale", 1);
  if (type == "point" || type == "spot") {
    glm::dvec3 intensity = light_colour(t, lookup(ps, what, "I", kSpectrumTypes), what) * scale;
    glm::dvec3 from = get_point(ps, what, "from", glm::dvec3(0));
    double power = get_float(ps, what, "power", -1);
    json light = {{"type", type}, {"position", vec_json(transform_point(l.ctm, from))}};
    if (type == "point") {
      if (power > 0) intensity *= power / (4 * kPi);
    } else {
      glm::dvec3 to = get_point(ps, what, "to", glm::dvec3(0, 0, 1));
      double cone = get_float(ps, what, "coneangle", 30), delta = get_float(ps, what, "conedeltaangle", 5);
      if (glm::length(to - from) == 0) fail(at, what + ": \"from\" and \"to\" coincide");
      if (!(cone > 0 && cone <= 180)) fail(at, what + ": coneangle " + num(cone) + " is not in (0, 180]");
      if (!is_similarity(glm::dmat3(l.ctm)))
        fail(at, what + ": its transform scales unevenly or shears, which makes its cone elliptical (not supported)");
      double inner = cone - delta;
      if (inner < 0 || inner > cone) {
        warn(t, at, what + ": coneangle - conedeltaangle = " + num(inner) + " is outside [0, coneangle]: clamped");
        inner = std::clamp(inner, 0.0, cone);
      }
      if (power > 0) {
        // pbrt-v4's SpotLight::Create: the smoothstep falloff's solid angle.
        double cos_end = std::cos(cone * kPi / 180), cos_start = std::cos(inner * kPi / 180);
        intensity *= power / (2 * kPi * ((1 - cos_start) + (cos_start - cos_end) / 2));
      }
      light["direction"] = vec_json(transform_vector(l.ctm, to - from));
      light["outer_angle_degrees"] = cone;
      light["inner_angle_degrees"] = inner;
    }
    light["intensity"] = vec_json(intensity);
    push_light(t, std::move(light), at, what);
  } else if (type == "distant") {
    glm::dvec3 irradiance = light_colour(t, lookup(ps, what, "L", kSpectrumTypes), what) * scale;
    glm::dvec3 from = get_point(ps, what, "from", glm::dvec3(0)), to = get_point(ps, what, "to", glm::dvec3(0, 0, 1));
    if (glm::length(to - from) == 0) fail(at, what + ": \"from\" and \"to\" coincide");
    // Light travels from "from" towards "to"; "illuminance" is the irradiance of a surface facing it.
    if (double e = get_float(ps, what, "illuminance", -1); e > 0) irradiance *= e;
    push_light(t, {{"type", "directional"}, {"direction", vec_json(transform_vector(l.ctm, to - from))},
                   {"irradiance", vec_json(irradiance)}},
               at, what);
  } else {  // infinite
    std::string filename = get_string(ps, what, "filename", "");
    const Param* L = lookup(ps, what, "L", kSpectrumTypes);
    if (!filename.empty() && L)
      fail(L->place, what + ": \"L\" and \"filename\" together (pbrt-v4 refuses them: an image light takes its "
                            "radiance from the image)");
    if (L && (L->type == "rgb" ? L->numbers.size() != 3 : L->type == "spectrum" && L->strings.size() > 1))
      fail(L->place, what + ": expected one value of " + L->decl() + " (an image is not supported)");
    if (const Param* portal = lookup(ps, what, "portal", {"point3"}))
      warn(t, portal->place, what + ": the portal is dropped: pathcl samples the whole sky (the same image where the "
                                     "portal is the only opening, with more noise)");
    if (!filename.empty()) {
      if (t.environment >= 0)
        fail(at, what + ": a second environment light (pathcl has one; an image light cannot be added to the "
                        "environment of " + origin_of(t, t.environment) + ")");
      t.environment = int(t.lights.size());
      push_light(t, image_environment(t, l, filename, scale), at, what);
    } else {
      glm::dvec3 radiance = light_colour(t, L, what) * scale;
      // "illuminance": that of an upward-facing surface under the whole uniform sky, pi L.
      if (double e = get_float(ps, what, "illuminance", -1); e > 0) radiance *= e / kPi;
      if (t.environment >= 0) {
        // One environment light in pathcl: uniform skies add up.
        json& env = t.lights[t.environment];
        if (env.contains("file"))
          fail(at, what + ": a second environment light (pathcl has one; a uniform light cannot be added to the "
                          "image light of " + origin_of(t, t.environment) + ")");
        env["radiance"] = vec_json(glm::dvec3(env["radiance"][0], env["radiance"][1], env["radiance"][2]) + radiance);
      } else {
        t.environment = int(t.lights.size());
        push_light(t, {{"type", "environment"}, {"radiance", vec_json(radiance)}}, at, what);
      }
    }
  }
  warn_unused(t.messages, ps, what);
}

// ----- Camera, film and filter

json translate_filter(Translator& t) {
  // pbrt-v4's default filter is a Gaussian of radius 1.5 and sigma 0.5.
  Entity f = t.scene.filter ? *t.scene.filter : Entity{"PixelFilter", "gaussian", Place{t.main_file, 0, t.main_dir}, {}};
  const Params& ps = f.params;
  const std::string what = f.what();
  const std::string& type = f.type;
  double def = type == "box" ? 0.5 : type == "gaussian" ? 1.5 : type == "mitchell" ? 2 : type == "triangle" ? 2 : 4;
  double rx = get_float(ps, what, "xradius", def), ry = get_float(ps, what, "yradius", def);
  Place at = f.place.line ? f.place : Place{t.main_file, 0, t.main_dir};
  auto where = [&] { return f.place.line ? what : "pbrt-v4's default filter, " + what; };
  if (rx != ry) warn(t, at, where() + ": xradius " + num(rx) + " and yradius " + num(ry) + " differ: pathcl's filters are "
                                      "the same along both axes, radius " + num(rx) + " is used");
  json out;
  if (type == "box") {
    if (rx != 0.5) warn(t, at, where() + ": radius " + num(rx) + ": pathcl's box filter is one pixel wide (radius 0.5)");
    out = {{"type", "box"}};
  } else if (type == "triangle") {
    out = {{"type", "tent"}, {"radius", rx}};
  } else if (type == "gaussian") {
    double sigma = get_float(ps, what, "sigma", 0.5);
    warn(t, at, where() + ": pbrt-v4 subtracts the Gaussian's value at the radius (" + num(rx) + "), pathcl cuts the "
                          "Gaussian off there: pixel weights differ slightly");
    out = {{"type", "gaussian"}, {"sigma", sigma}, {"radius", rx}};
  } else {  // mitchell, sinc (lanczos)
    get_float(ps, what, "B", 1.0 / 3);
    get_float(ps, what, "C", 1.0 / 3);
    get_float(ps, what, "tau", 3);
    warn(t, at, where() + " is not supported (its negative lobes): pathcl's box filter is used");
    out = {{"type", "box"}};
  }
  warn_unused(t.messages, ps, what);
  if (f.place.line) t.origins.push_back({"camera.filter", f.place.str() + ": " + what});
  return out;
}

struct Film {
  int width = 1280, height = 720;
};

Film translate_film(Translator& t, double exposure_time) {
  Film film;
  if (!t.scene.film) return film;
  const Entity& f = *t.scene.film;
  const Params& ps = f.params;
  const std::string what = f.what();
  const Place& at = f.place;
  film.width = get_int(ps, what, "xresolution", 1280);
  film.height = get_int(ps, what, "yresolution", 720);
  if (film.width < 1 || film.width > 16384 || film.height < 1 || film.height > 16384)
    fail(at, what + ": resolution " + std::to_string(film.width) + " x " + std::to_string(film.height) +
                 " is outside pathcl's 1 to 16384 pixels a side");
  if (f.type != "rgb" && f.type != "image") warn(t, at, what + " is rendered as an RGB image");
  std::vector<double> crop = get_floats(ps, what, "cropwindow");
  if (!crop.empty() && crop != std::vector<double>{0, 1, 0, 1})
    fail(at, what + ": cropwindow is not supported (pathcl renders the whole image)");
  std::vector<int> bounds = get_ints(ps, what, "pixelbounds");
  if (!bounds.empty() && bounds != std::vector<int>{0, film.width, 0, film.height})
    fail(at, what + ": pixelbounds is not supported (pathcl renders the whole image)");
  std::vector<std::string> output;
  if (const Param* p = lookup(ps, what, "filename", {"string"})) output.push_back(p->decl());
  if (const Param* p = lookup(ps, what, "savefp16", {"bool"})) output.push_back(p->decl());
  if (!output.empty())
    warn(t, at, what + ": " + join(output) + " ignored: pathcl writes its image where its --output option says");
  get_float(ps, what, "diagonal", 35);  // the realistic camera's, which is refused
  double iso = get_float(ps, what, "iso", 100), white = get_float(ps, what, "whitebalance", 0);
  std::string sensor = get_string(ps, what, "sensor", "cie1931");
  double ratio = exposure_time * iso / 100;
  if (ratio != 1)
    warn(t, at, what + ": pbrt-v4 multiplies the image by " + num(ratio) + " (exposure time " + num(exposure_time) +
                    " times ISO " + num(iso) + " / 100); pathcl does not: scale its result by that");
  if (sensor != "cie1931" || white != 0)
    warn(t, at, what + ": sensor " + in_quotes(sensor) + " and white balance " + num(white) + " are not simulated (pathcl "
                       "writes the scene's linear sRGB)");
  if (double m = get_float(ps, what, "maxcomponentvalue", INFINITY); std::isfinite(m))
    warn(t, at, what + ": maxcomponentvalue " + num(m) + ": pathcl does not clamp samples");
  for (const char* name : {"coordinatesystem", "nbuckets", "lambdamin", "lambdamax"})
    if (const Param* p = lookup(ps, what, name, {"string", "integer", "float", "bool"}))
      warn(t, p->place, what + ": " + p->decl() + " ignored (pathcl writes an RGB image)");
  warn_unused(t.messages, ps, what);
  t.origins.push_back({"camera.width", at.str() + ": " + what});
  t.origins.push_back({"camera.height", at.str() + ": " + what});
  return film;
}

json translate_camera(Translator& t) {
  Entity cam = t.scene.camera ? *t.scene.camera : Entity{"Camera", "perspective", Place{t.main_file, 0, t.main_dir}, {}};
  const Params& ps = cam.params;
  const std::string what = cam.what();
  const Place at = cam.place.line ? cam.place : Place{t.main_file, 1, t.main_dir};
  if (cam.type != "perspective")
    fail(at, "Camera " + in_quotes(cam.type) + " is not supported (supported: perspective)");
  if (!t.scene.camera_medium.empty())
    fail(at, what + ": participating media are not supported (the camera is in medium " + in_quotes(t.scene.camera_medium) + ")");
  double open = get_float(ps, what, "shutteropen", 0), close = get_float(ps, what, "shutterclose", 1);
  Film film = translate_film(t, std::abs(close - open));

  // pbrt's camera space: +x the image's right, +y up, +z forward (cameras.cpp), placed by the inverse of the
  // CTM at Camera.
  const glm::dmat4& camera_from_world = t.scene.camera_from_world;
  if (!is_affine(camera_from_world) || glm::determinant(glm::dmat3(camera_from_world)) == 0)
    fail(at, what + ": the camera transform is projective or singular");
  glm::dmat4 world_from_camera = glm::inverse(camera_from_world);
  glm::dvec3 position = transform_point(world_from_camera, glm::dvec3(0));
  glm::dvec3 right = transform_vector(world_from_camera, {1, 0, 0}), up = transform_vector(world_from_camera, {0, 1, 0});
  glm::dvec3 forward = transform_vector(world_from_camera, {0, 0, 1});
  double s = glm::length(forward);
  // Exporters write matrices to 6 digits (Bitterli's scenes: columns 2e-5 from orthogonal): a frame within
  // 1e-4 of a rotation is taken as its rotation (the view moves by at most 1e-4 radians), with a warning
  // beyond 1e-6; a larger shear or uneven scale would distort pbrt's image, which pathcl's camera cannot.
  const double camera_error = similarity_error(glm::dmat3(right, up, forward));
  if (camera_error > 1e-4)
    fail(at, what + ": the camera transform scales unevenly or shears (pbrt would render a distorted image; pathcl's "
                    "camera is a rotation and a position)");
  if (camera_error > 1e-6)
    warn(t, at, what + ": the camera transform is " + num(camera_error) +
                    " from a rotation (a matrix written with few digits): pathcl builds the camera's frame from its view "
                    "direction and up");

  // "fov" spans the shorter image axis: the screen window is [-frame, frame] x [-1, 1] for a wide image and
  // [-1, 1] x [-1/frame, 1/frame] for a tall one, and a screen unit is tan(fov / 2) ahead at distance 1.
  double aspect = double(film.width) / film.height;
  double frame = get_float(ps, what, "frameaspectratio", aspect);
  double x1 = frame > 1 ? frame : 1, y1 = frame > 1 ? 1 : 1 / frame;
  std::vector<double> window = get_floats(ps, what, "screenwindow");
  if (!window.empty()) {
    if (window.size() != 4) fail(at, what + ": screenwindow takes 4 numbers");
    x1 = window[1];
    y1 = window[3];
    if (window[0] != -window[1] || window[2] != -window[3] || !(x1 > 0 && y1 > 0))
      fail(at, what + ": an off-centre screenwindow is not supported (pathcl's images are centred on the view direction)");
  }
  if (std::abs(x1 / y1 - aspect) > 1e-5 * aspect)
    fail(at, what + ": the screen window's aspect ratio " + num(x1 / y1) + " differs from the film's " + num(aspect) +
                 " (non-square pixels are not supported)");
  double fov = get_float(ps, what, "fov", 90);
  if (!(fov > 0 && fov < 180)) fail(at, what + ": fov " + num(fov) + " is not in (0, 180)");
  double fov_y = 2 * std::atan(y1 * std::tan(fov * kPi / 360)) * 180 / kPi;

  // pbrt's camera +x is usually cross(up, forward) (LookAt): left-handed.
  json camera = camera_frame_json(position, forward / s, up / s, right);
  camera["fov_y_degrees"] = fov_y;
  camera["width"] = film.width;
  camera["height"] = film.height;
  double lens = get_float(ps, what, "lensradius", 0), focus = get_float(ps, what, "focaldistance", 1e6);
  if (lens > 0) {
    camera["type"] = "thin_lens";
    camera["aperture_radius"] = lens * s;
    camera["focus_distance"] = focus * s;
  } else {
    camera["type"] = "perspective";
  }
  camera["filter"] = translate_filter(t);
  if (open != 0 || close != 1)
    warn(t, at, what + ": the shutter (" + num(open) + " to " + num(close) + ") matters for motion blur, which is not rendered");
  warn_unused(t.messages, ps, what);
  t.origins.push_back({"camera", cam.place.line ? at.str() + ": " + what : t.main_file + ": pbrt-v4's default camera"});
  return camera;
}

// ----- Render settings

json translate_render(Translator& t) {
  json render;
  long long seed = t.scene.option_seed.value_or(0);
  // Sampler: pbrt-v4's default is zsobol with 16 samples a pixel.
  Entity smp = t.scene.sampler ? *t.scene.sampler : Entity{"Sampler", "zsobol", Place{t.main_file, 0, t.main_dir}, {}};
  {
    const Params& ps = smp.params;
    const std::string what = smp.what();
    const Place& at = smp.place;
    const std::string& type = smp.type;
    long long spp;
    if (type == "stratified") {
      spp = (long long)get_int(ps, what, "xsamples", 4) * get_int(ps, what, "ysamples", 4);
      if (!get_bool(ps, what, "jitter", true)) warn(t, at, what + ": jitter false: pathcl's strata are always jittered");
      render["sampler"] = "stratified";
    } else {
      spp = get_int(ps, what, "pixelsamples", type == "independent" ? 4 : 16);
      render["sampler"] = type == "independent" ? "independent" : type == "halton" ? "halton" : "sobol";
      if (type == "pmj02bn" || type == "02sequence" || type == "lowdiscrepancy" || type == "maxmindist")
        warn(t, at, what + " is rendered with pathcl's sobol sampler (Owen-scrambled)");
    }
    if (const Param* r = lookup(ps, what, "randomization", {"string"}))
      warn(t, r->place, what + ": randomization " + in_quotes(one_value(r)->strings[0]) + " ignored: pathcl scrambles its " +
                            "own way (Owen scrambling)");
    if (spp < 1 || spp > (1 << 24)) fail(at, what + ": " + std::to_string(spp) + " samples a pixel is outside pathcl's 1 to 16777216");
    if (const Param* sd = lookup(ps, what, "seed", {"integer"})) seed = (long long)one_value(sd)->numbers[0];
    render["spp"] = spp;
    warn_unused(t.messages, ps, what);
    if (smp.place.line) t.origins.push_back({"render.spp", at.str() + ": " + what});
  }
  // Integrator: pbrt-v4's default is volpath, maxdepth 5. pbrt's maxdepth counts scattering events as pathcl's
  // max_depth does: 0 is emission seen directly, 1 direct lighting (PathIntegrator::Li: "if (depth++ == maxDepth)").
  Entity in = t.scene.integrator ? *t.scene.integrator : Entity{"Integrator", "volpath", Place{t.main_file, 0, t.main_dir}, {}};
  {
    const Params& ps = in.params;
    const std::string what = in.what();
    const Place& at = in.place;
    const std::string& type = in.type;
    if (one_of(type, {"ambientocclusion", "aov", "function", "directlighting", "whitted"}))
      fail(at, "Integrator " + in_quotes(type) + " is not supported (supported: volpath, path, bdpt, lightpath, sppm, mlt; "
                                             "simplepath, simplevolpath and randomwalk as path)");
    int depth = get_int(ps, what, "maxdepth", 5);
    if (depth < 0) fail(at, what + ": maxdepth " + std::to_string(depth) + " is negative");
    const int most = type == "mlt" ? 16 : 1024;  // pathcl's mlt keeps a chain's numbers for up to 16 events
    if (depth > most) {
      warn(t, at, what + ": maxdepth " + std::to_string(depth) + " is beyond pathcl's largest" +
                      (type == "mlt" ? " for mlt" : "") + ", " + std::to_string(most) + ": " + std::to_string(most) + " is used");
      depth = most;
    }
    render["max_depth"] = depth;
    if (type == "volpath" || type == "path") {
      render["integrator"] = "path";
    } else if (type == "bdpt") {
      render["integrator"] = "bdpt";
      for (const char* name : {"visualizestrategies", "visualizeweights"})
        if (get_bool(ps, what, name, false)) warn(t, at, what + ": " + name + " ignored (pathcl writes the image)");
    } else if (type == "lightpath") {
      render["integrator"] = "light";
    } else if (type == "mlt") {
      // pbrt-v4's MLTIntegrator: multiplexed primary-sample-space MLT over BDPT, as pathcl's; mutationsperpixel
      // mutations a pixel (the sampler's samples unused), a chain per pixel in pathcl.
      const int bootstrap = get_int(ps, what, "bootstrapsamples", 100000);
      const double large = get_float(ps, what, "largestepprobability", 0.3), sigma = get_float(ps, what, "sigma", 0.01);
      if (bootstrap < 1 || bootstrap > (1 << 20)) fail(at, what + ": bootstrapsamples " + std::to_string(bootstrap) + " is outside 1 to 1048576");
      if (!(large >= 0 && large <= 1)) fail(at, what + ": largestepprobability " + num(large) + " is outside [0, 1]");
      if (!(sigma > 0 && sigma <= 1)) fail(at, what + ": sigma " + num(sigma) + " is outside (0, 1]");
      render["integrator"] = {{"type", "mlt"}, {"bootstrap", bootstrap}, {"large_step", large}, {"mutation_size", sigma}};
      const int mutations = get_int(ps, what, "mutationsperpixel", 100);
      if (mutations < 1 || mutations > (1 << 24)) fail(at, what + ": mutationsperpixel " + std::to_string(mutations) + " is outside 1 to 16777216");
      render["spp"] = mutations;
      warn(t, at, what + ": sigma " + num(sigma) + " (the standard deviation of pbrt's Gaussian moves) is pathcl's " +
                      "mutation_size (the largest of Kelemen's exponential moves): other noise, the same image");
      if (const Param* chains = lookup(ps, what, "chains", {"integer"}))
        warn(t, chains->place, what + ": chains ignored (pathcl runs a chain per pixel)");
    } else if (type == "sppm") {
      // pbrt's "radius" (default 1) is the first iteration's search radius in scene units, as pathcl's.
      render["integrator"] = {{"type", "sppm"}, {"radius", get_float(ps, what, "radius", 1)}};
      if (const Param* photons = lookup(ps, what, "photonsperiteration", {"integer"}))
        warn(t, photons->place, what + ": photonsperiteration ignored (pathcl traces one light path per pixel and "
                                       "iteration)");
      if (const Param* sd = lookup(ps, what, "seed", {"integer"})) seed = (long long)one_value(sd)->numbers[0];
    } else {
      render["integrator"] = "path";
      warn(t, at, what + " is rendered with pathcl's path integrator (next-event estimation and multiple importance "
                         "sampling): the same image, with other noise");
      get_bool(ps, what, "samplelights", true);
      get_bool(ps, what, "samplebsdf", true);
    }
    if (const Param* ls = lookup(ps, what, "lightsampler", {"string"}); ls && one_value(ls)->strings[0] != "bvh")
      warn(t, ls->place, what + ": lightsampler " + in_quotes(ls->strings[0]) + " ignored (pathcl chooses lights with its "
                                                                            "light BVH, as pbrt's \"bvh\")");
    if (get_bool(ps, what, "regularize", false)) warn(t, at, what + ": regularize ignored (pathcl does not regularize)");
    warn_unused(t.messages, ps, what);
    if (in.place.line) t.origins.push_back({"render.max_depth", at.str() + ": " + what});
    if (in.place.line) t.origins.push_back({"render.integrator", at.str() + ": " + what});
  }
  if (seed < 0 || seed > 4294967295LL) {
    warn(t, t.scene.option_seed ? t.scene.option_seed_place : smp.place,
         "seed " + std::to_string(seed) + " is outside pathcl's 0 to 2^32 - 1: taken modulo 2^32");
    seed = (long long)(uint32_t)seed;
  }
  render["seed"] = seed;
  t.origins.push_back({"render", t.main_file + ": render settings (Sampler, Integrator)"});
  return render;
}

// ----- The whole scene

void translate_world(Translator& t) {
  for (const WorldItem& item : t.scene.world) {
    if (item.shape >= 0) {
      const ShapeEntity& s = t.scene.shapes[item.shape];
      translate_shape(t, {s, s.ctm, s.entity.place.str() + ": " + s.entity.what(), false});
      continue;
    }
    const InstanceUse& use = t.scene.instance_uses[item.instance];
    auto object = t.scene.objects.find(use.name);
    if (object == t.scene.objects.end()) fail(use.place, "ObjectInstance " + in_quotes(use.name) + ": no ObjectBegin defines it");
    // An instance places the object's shapes by the CTM at ObjectInstance times each shape's own CTM.
    for (const ShapeEntity& s : object->second)
      translate_shape(t, {s, use.ctm * s.ctm,
                          use.place.str() + ": ObjectInstance " + in_quotes(use.name) + " (" + s.entity.what() + " at " +
                              s.entity.place.str() + ")",
                          true});
  }
}

void check_unused(Translator& t) {
  for (const auto& [name, index] : t.scene.named_materials)
    if (!t.translated.count(index))
      warn(t, t.scene.materials[index].entity.place, "MakeNamedMaterial " + in_quotes(name) + " is used by no shape: left out");
  for (const auto& [name, place] : t.scene.media)
    warn(t, place, "MakeNamedMedium " + in_quotes(name) + " is used by nothing: left out (participating media are not supported)");
}

}  // namespace

ImportedScene import_pbrt(const std::string& path, const std::string& text) {
  Messages messages;
  Scene scene = parse_scene(messages, path, text);
  Translator t(scene, messages, path);
  // Named materials keep their names; generated names must not take them.
  for (const auto& [name, index] : scene.named_materials) t.names.insert(name);
  json out;
  out["camera"] = translate_camera(t);
  out["render"] = translate_render(t);
  translate_world(t);
  for (const LightEntity& l : scene.lights) translate_light(t, l);
  check_unused(t);
  out["materials"] = t.materials;
  out["shapes"] = t.shapes;
  if (!t.lights.empty()) out["lights"] = t.lights;
  ImportedScene result;
  result.scene = std::move(out);
  result.origins = std::move(t.origins);
  result.warnings = std::move(messages.warnings);
  return result;
}
