// Mitsuba 0.6 and 3 XML scene files as pathcl scenes (scene/scene_import.h; docs/scene-format.md).
#include "scene/scene_import.h"
#include "scene/scene_error.h"

ImportedScene import_mitsuba_xml(const std::string& path, const std::string& text) {
  throw SceneError(path + ": Mitsuba XML scenes are not read yet");
}
