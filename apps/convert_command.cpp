#include "apps/convert_command.h"

#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "runtime/atomic_file.h"
#include "runtime/errors.h"
#include "runtime/output_files.h"
#include "scene/scene_description.h"
#include "scene/scene_import.h"

namespace {

struct ConvertArgs {
  std::string input, output;
  std::vector<std::string> defines;
  bool quiet = false;
  CLI::App* command = nullptr;
};

ConvertArgs& args() {
  static ConvertArgs a;
  return a;
}

}  // namespace

void add_convert_command(CLI::App& app) {
  ConvertArgs& a = args();
  a.command = app.add_subcommand("convert", "write a Mitsuba XML or pbrt-v4 scene as a pathcl JSON scene");
  a.command->add_option("scene", a.input, "scene file (Mitsuba 0.6 or 3 XML, pbrt-v4)")->required();
  a.command->add_option("-D,--define", a.defines, "NAME=VALUE: a Mitsuba scene's <default> value (repeatable)");
  a.command->add_option("-o,--output", a.output, "the JSON scene to write (default: SCENE-NAME.json beside it)");
  a.command->add_flag("-q,--quiet", a.quiet, "no warnings or summary on stderr");
}

bool convert_command_parsed() { return args().command && args().command->parsed(); }

int run_convert_command() {
  namespace fs = std::filesystem;
  const ConvertArgs& a = args();
  const std::string output = a.output.empty() ? fs::path(a.input).replace_extension(".json").string() : a.output;
  const SceneDefines defines = parse_scene_defines(a.defines);
  ImportedScene document = load_scene_document(a.input, defines);
  if (document.format == SceneFileFormat::json)
    throw UsageError(a.input + ": is a pathcl JSON scene already (convert reads Mitsuba XML and pbrt scenes)");
  std::error_code ignored;
  if (fs::equivalent(a.input, output, ignored))
    throw UsageError("-o " + output + ": is the scene being converted (choose another file)");
  check_output_files({{"-o", output}});
  // Every check a render makes (meshes, images, ranges): what convert writes is a scene pathcl renders.
  const SceneDescription scene = load_scene(a.input, document);
  rebase_scene_paths(document.scene, fs::path(a.input).parent_path().string(), fs::path(output).parent_path().string());
  write_text_file(output, scene_json_text(document.scene));
  if (!a.quiet) {
    for (const std::string& w : scene.warnings) std::fprintf(stderr, "warning: %s\n", w.c_str());
    std::fprintf(stderr, "%s -> %s: %zu materials, %zu shapes, %zu lights\n", a.input.c_str(), output.c_str(),
                 document.scene.value("materials", nlohmann::json::object()).size(),
                 document.scene.value("shapes", nlohmann::json::array()).size(),
                 document.scene.value("lights", nlohmann::json::array()).size());
  }
  return 0;
}
