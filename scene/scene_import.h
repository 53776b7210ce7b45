// Scene files of other renderers (Mitsuba 0.6 and 3 XML, pbrt-v4) translated into a pathcl scene: the JSON
// document of docs/scene-format.md, which load_scene then checks and loads like any JSON scene. One
// loader, one set of checks; `pathcl convert` writes the document out.
#pragma once
#include <string>
#include <utility>
#include <vector>

#include <glm/mat4x4.hpp>
#include <glm/vec3.hpp>
#include <nlohmann/json.hpp>

enum class SceneFileFormat { json, mitsuba_xml, pbrt };

// Values for a Mitsuba scene's <default>s, as Mitsuba's `-D NAME=VALUE` sets them: they win over the file's.
using SceneDefines = std::vector<std::pair<std::string, std::string>>;
// "NAME=VALUE" words (the command line's -D) as defines; SceneError naming a word without '=' or a name.
SceneDefines parse_scene_defines(const std::vector<std::string>& words);

struct ImportedScene {
  // The pathcl scene. Mesh and image paths in it are as the source file wrote them, resolved against
  // the source file's directory (absolute paths stay absolute).
  nlohmann::json scene;
  // Where each entry came from, for messages about it: a JSON path ("camera", "materials.gray",
  // "shapes[3]", "lights[0]", "render") and the source place ("cbox.xml:34: shape \"obj\""). An error
  // that the JSON checks find at "shapes[3].radius" is reported at the longest such prefix.
  std::vector<std::pair<std::string, std::string>> origins;
  // What the translation approximated or left out, each naming its place ("cbox.xml:12: ...").
  std::vector<std::string> warnings;
  SceneFileFormat format = SceneFileFormat::json;  // what the file was (set by load_scene_document)
};

// Told by content, not by name: '<' first (after a byte order mark, white space and XML comments) is
// Mitsuba XML; a first word that is a pbrt directive (or a '#' comment followed by one) is pbrt; anything
// else is read as JSON.
SceneFileFormat scene_file_format(const std::string& text);

// The document of any scene file: a JSON file parsed (and scanned for keys given twice), a Mitsuba or
// pbrt file translated. Throws SceneError naming the file and place.
// `defines` are for Mitsuba files only: SceneError for a JSON or pbrt file given any.
ImportedScene load_scene_document(const std::string& path, const SceneDefines& defines = {});

// The scene of a document that load_scene_document read from `path` (relative files resolved beside it): what
// load_scene(path) gives, without reading and translating the file again.
struct SceneDescription;
SceneDescription load_scene(const std::string& path, const ImportedScene& document);

// Mesh, image and glTF paths of a document (shapes' `file`, textures, environment maps, `from_gltf`)
// written relative to `to_dir` instead of `from_dir` (absolute paths stay): a converted scene written to
// another directory still names the source's files.
void rebase_scene_paths(nlohmann::json& scene, const std::string& from_dir, const std::string& to_dir);

// The document as a scene file: JSON, two spaces a level, arrays of numbers on one line (a converted
// mesh's positions one vertex a line), numbers as the shortest text that reads back as the same double.
std::string scene_json_text(const nlohmann::json& scene);

// Each throws SceneError naming the file and line ("cbox.xml:12: ...") on bad or unsupported input.
ImportedScene import_mitsuba_xml(const std::string& path, const std::string& text, const SceneDefines& defines = {});
ImportedScene import_pbrt(const std::string& path, const std::string& text);

// ---- What both importers write into the document.

nlohmann::json vec_json(const glm::dvec3& v);     // [x, y, z]
nlohmann::json matrix_json(const glm::dmat4& m);  // a transform's "matrix": 4 rows of 4 numbers
// Whether every entry is within `tolerance` of the identity's (false for a NaN).
bool is_identity(const glm::dmat4& m, double tolerance = 0);
glm::dvec3 transform_point(const glm::dmat4& m, const glm::dvec3& p);
glm::dvec3 transform_vector(const glm::dmat4& m, const glm::dvec3& v);
// The camera's "position", "look_at" (position + forward) and "up" as given, and "handedness": "left" where the
// image's right is cross(up, forward), the mirror of pathcl's cross(forward, up) (pbrt's LookAt frame, a
// mirroring Mitsuba to_world).
nlohmann::json camera_frame_json(const glm::dvec3& position, const glm::dvec3& forward, const glm::dvec3& up,
                                 const glm::dvec3& image_right);
