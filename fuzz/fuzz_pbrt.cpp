// libFuzzer target: a pbrt-v4 scene file through load_scene (scene/scene_import.h: the pbrt reader, then the
// JSON checks, the meshes it names and build_device_scene). Bad input must end in SceneError; any other
// exception, crash or sanitizer report is a bug. The file lies next to a valid unit cube (m.obj), which
// shapes may name. Run by scripts/fuzz.
#include <cstdint>
#include <string>

#include "fuzz/fuzz_common.h"
#include "scene/device_scene_build.h"
#include "scene/scene_description.h"
#include "scene/scene_error.h"
#include "scene/scene_import.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size > fuzz::kMaxInputBytes) return 0;
  const std::string path = fuzz::scratch().write("s.pbrt", data, size);
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    // The reader itself (whatever the content looks like), then the whole way a render takes.
    import_pbrt(path, text);
    if (scene_file_format(text) == SceneFileFormat::pbrt) build_device_scene(load_scene(path));
  } catch (const SceneError&) {
  }
  return 0;
}
