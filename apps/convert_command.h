// `pathcl convert SCENE -o scene.json`: a Mitsuba XML or pbrt scene written as the equivalent pathcl JSON
// scene (scene/scene_import.h), its mesh and image files referenced from where the JSON is written.
#pragma once

namespace CLI {
class App;
}

void add_convert_command(CLI::App& app);
bool convert_command_parsed();
// Loads the scene completely (every check of a render, meshes and images included), then writes the
// JSON; warnings go to stderr. Bad input throws SceneError or UsageError (exit 2).
int run_convert_command();
