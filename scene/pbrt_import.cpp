// pbrt-v4 scene files as pathcl scenes (scene/scene_import.h; docs/scene-format.md).
#include "scene/scene_import.h"
#include "scene/scene_error.h"

ImportedScene import_pbrt(const std::string& path, const std::string& text) {
  throw SceneError(path + ": pbrt scenes are not read yet");
}
