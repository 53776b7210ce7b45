// The command line: exit codes, messages, and that bad input never leaves an output file.
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "runtime/cl_check.h"
#include "runtime/image_io.h"
#include "test_support.h"

namespace fs = std::filesystem;

namespace {

std::string scene(const std::string& name) { return std::string(PATHCL_TEST_SCENES) + "/" + name; }

}  // namespace

TEST(Cli, BadInputExitsWithTwoAndWritesNothing) {
  struct Case {
    std::string args, message;
  } cases[] = {
      {scene("bad-malformed.json"), "malformed JSON"},
      {scene("bad-unknown-key.json"), "unknown key \"colour\""},
      {scene("bad-missing-obj.json"), "cannot open the mesh file"},
      {scene("bad-face-index.json"), "bad-face-index.obj:7: face index 9 out of range"},
      {scene("bad-nan-vertex.json"), "nan-vertex.obj:2"},
      {scene("bad-no-faces.json"), "meshes/no-faces.ply: no faces (1 vertices: a point cloud? pathcl renders surfaces)"},
      {scene("bad-truncated-stl.json"), "meshes/truncated.stl: truncated or garbled binary STL file"},
      {scene("bad-lfs-mesh.json"), "meshes/lfs-pointer.off: looks like a Git LFS pointer, not a mesh (run git lfs pull)"},
      {scene("bad-unknown-material.json"), "unknown material \"glas\""},
      {scene("bad-negative-spp.json"), "render.spp"},
      {scene("bad-huge-sphere.json"), "shapes[0].radius: a sphere radius of 1e+30 is beyond the largest of 1.5e+18"},
      {scene("tiny.json") + " --spp -3", "--spp"},
      {scene("bad-integrator.json"), "render.integrator: unknown integrator \"lite\" (expected path, light, bdpt, vcm, bpm, sppm, instant_radiosity, radiosity or mlt)"},
      {scene("tiny.json") + " --integrator foo", "--integrator: unknown integrator \"foo\" (expected path, light, bdpt, vcm, bpm, sppm, instant_radiosity, radiosity or mlt)"},
      {scene("instances.json") + " --integrator radiosity",
       "the radiosity integrator keeps one power sum per triangle and takes no instanced meshes (the scene places "},
      {scene("tiny.json") + " --device no-such-device-xyz", "no-such-device-xyz"},
      {scene("tiny.json") + " --device 99", "no device with that index"},
      {scene("no-such-scene.json"), "cannot open the scene file"},
      {std::string(PATHCL_TEST_SCENES) + "/meshes", "meshes: is a directory, expected a JSON scene file"},
  };
  for (const Case& c : cases) {
    std::string out = temp_dir() + "/bad.exr", png = temp_dir() + "/bad.png", stats = temp_dir() + "/bad.json";
    std::string err;
    int code = run_pathcl("render " + c.args + " -o " + out + " --png " + png + " --stats " + stats, &err);
    EXPECT_EQ(code, 2) << c.args << "\n" << err;
    EXPECT_NE(err.find(c.message), std::string::npos) << c.args << "\n" << err;
    EXPECT_FALSE(fs::exists(out) || fs::exists(png) || fs::exists(stats)) << c.args;
  }
  EXPECT_EQ(run_pathcl("render"), 2);
  EXPECT_EQ(run_pathcl("frobnicate"), 2);
}

// The bad files issue 16 lists, each written here: `pathcl render` names the file and what is wrong, exits
// with status 2 and writes nothing.
TEST(Cli, BadMeshGltfAndImageFilesExitWithTwoAndNameTheFile) {
  auto u32 = [](uint32_t v) { return std::string(reinterpret_cast<const char*>(&v), 4); };
  std::string doc = R"({"asset": {"version": "2.0"}})";
  while (doc.size() % 4) doc += ' ';
  const std::string glb = "glTF" + u32(2) + u32(uint32_t(20 + doc.size())) + u32(uint32_t(doc.size())) + "JSON" + doc;
  const std::string lfs = "version https://git-lfs.github.com/spec/v1\noid sha256:0123\nsize 4096\n";
  const std::string camera = R"("camera": {"position": [0, 0, 5], "look_at": [0, 0, 0], "width": 8, "height": 8})";
  auto mesh_scene = [&](const std::string& file) {
    return "{" + camera + R"(, "materials": {"m": {"type": "diffuse"}}, "shapes": [{"type": "mesh", "file": ")" + file +
           R"(", "material": "m"}]})";
  };
  auto gltf_scene = [&](const std::string& file) {
    return "{" + camera + R"(, "materials": {}, "shapes": [{"type": "gltf", "file": ")" + file + R"("}]})";
  };
  auto texture_scene = [&](const std::string& file) {
    return "{" + camera + R"(, "materials": {"m": {"type": "diffuse", "reflectance": {"texture": ")" + file +
           R"("}}}, "shapes": [{"type": "triangles", "material": "m", "positions": [[0, 0, 0], [1, 0, 0], [0, 1, 0]],
           "indices": [[0, 1, 2]], "uvs": [[0, 0], [1, 0], [0, 1]]}]})";
  };
  struct Case {
    std::string file, content, scene, message;
  } cases[] = {
      {"points.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\nend_header\n0 0 0\n",
       mesh_scene("points.ply"), "no faces (1 vertices: a point cloud? pathcl renders surfaces)"},
      {"truncated.glb", glb.substr(0, 24), gltf_scene("truncated.glb"),
       "truncated GLB file: its header says " + std::to_string(glb.size()) + " bytes, but the file has 24"},
      {"draco.gltf", R"({"asset": {"version": "2.0"}, "extensionsUsed": ["KHR_draco_mesh_compression"],
                       "extensionsRequired": ["KHR_draco_mesh_compression"]})",
       gltf_scene("draco.gltf"), "requires the extension KHR_draco_mesh_compression, which pathcl does not support"},
      {"scan.tif", std::string("MM\x00*", 4), texture_scene("scan.tif"), "TIFF images are not supported"},
      {"notes.png", "these are not pixels", texture_scene("notes.png"), "unrecognised image format"},
      {"bunny.ply", lfs, mesh_scene("bunny.ply"), "looks like a Git LFS pointer, not a mesh (run git lfs pull)"},
      {"bunny.obj", lfs, mesh_scene("bunny.obj"), "looks like a Git LFS pointer, not a mesh (run git lfs pull)"},
      {"lantern.glb", lfs, gltf_scene("lantern.glb"), "looks like a Git LFS pointer, not a mesh (run git lfs pull)"},
  };
  for (const Case& c : cases) {
    const std::string file = write_temp_file("bad-files/" + c.file, c.content);
    const std::string scene = write_temp_file("bad-files/" + c.file + ".json", c.scene);
    const std::string out = temp_dir() + "/bad-file.exr";
    std::string err;
    EXPECT_EQ(run_pathcl("render " + scene + " -o " + out, &err), 2) << c.file << "\n" << err;
    EXPECT_NE(err.find(file + ": " + c.message), std::string::npos) << c.file << "\n" << err;
    EXPECT_FALSE(fs::exists(out)) << c.file;
  }
}

TEST(Cli, RenderWritesExrPngAndStats) {
  std::string out = temp_dir() + "/tiny.exr", png = temp_dir() + "/tiny.png", stats = temp_dir() + "/tiny.json";
  std::string err;
  ASSERT_EQ(run_pathcl("render " + scene("tiny.json") + " -o " + out + " --png " + png + " --stats " + stats +
                       " --spp 3 --seed 5 --max-depth 2", &err), 0) << err;
  Image image = read_exr(out);
  EXPECT_EQ(image.width, 24u);
  EXPECT_EQ(image.height, 16u);
  EXPECT_EQ(image.spp, 3);
  EXPECT_TRUE(fs::file_size(png) > 0);
  nlohmann::json j = nlohmann::json::parse(std::ifstream(stats));
  for (const char* key : {"device", "width", "height", "spp", "seed", "max_depth", "triangles", "bvh_nodes", "sah_cost",
                          "bvh_build_ms", "kernel_build_ms", "kernel_from_cache", "render_seconds", "samples_per_second",
                          "rays_traced", "rays_per_second", "nan_samples", "inf_samples", "negative_samples"})
    EXPECT_TRUE(j.contains(key)) << key;
  EXPECT_EQ(j["spp"], 3);
  EXPECT_EQ(j["seed"], 5);
  EXPECT_EQ(j["max_depth"], 2);
  EXPECT_EQ(j["triangles"], 8);  // 3 quads of the box + the 2-triangle lamp
  // One device: the scene was built with its BVH layout alone, and the figures name that one.
  EXPECT_EQ(int(j.contains("bvh4_nodes")) + int(j.contains("bvh8_nodes")) + int(j.contains("bvh16_nodes")), 1) << j.dump();
  EXPECT_EQ(j["nan_samples"], 0);
  EXPECT_GE(j["rays_traced"].get<double>(), 24 * 16 * 3);

  // A second render of the same features takes the kernel from the cache.
  ASSERT_EQ(run_pathcl("render " + scene("tiny.json") + " -o " + out + " --stats " + stats + " --spp 1"), 0);
  EXPECT_TRUE(nlohmann::json::parse(std::ifstream(stats))["kernel_from_cache"].get<bool>());
  EXPECT_EQ(read_exr(out).attributes.count("merging_radius"), 0u);

  // The merging integrators' settings, in the statistics and the EXR header: vcm's merge_mis where the
  // scene sets it (and its default, 0.25, where not), bpm without one.
  nlohmann::json tiny = nlohmann::json::parse(read_text_file(scene("tiny.json")));
  tiny["shapes"][0]["file"] = fs::absolute(fs::path(scene("tiny.json")).parent_path() / tiny["shapes"][0]["file"].get<std::string>()).string();
  tiny["render"]["integrator"] = {{"type", "vcm"}, {"radius", 0.5}, {"merge_mis", 1}};
  const std::string vcm = write_temp_file("vcm-tiny.json", tiny.dump());
  for (const auto& [args, mis] : std::vector<std::pair<std::string, double>>{{vcm, 1.0}, {scene("tiny.json") + " --integrator vcm", 0.25},
                                                                             {scene("tiny.json") + " --integrator bpm", 0.0}}) {
    ASSERT_EQ(run_pathcl("render " + args + " --spp 1 --lanes 1 -o " + out + " --stats " + stats, &err), 0) << err;
    j = nlohmann::json::parse(std::ifstream(stats));
    const std::map<std::string, std::string> header = read_exr(out).attributes;
    for (const char* key : {"merging_radius", "merging_alpha"}) {
      ASSERT_TRUE(j.contains(key)) << args << ": " << key;
      EXPECT_EQ(header.at(key), j[key].dump()) << args << ": " << key;
    }
    EXPECT_GT(j["merging_radius"].get<double>(), 0.0);
    if (args == vcm) {
      EXPECT_EQ(j["merging_radius"], 0.5);
    }
    EXPECT_EQ(j["merging_alpha"], 0.75);
    if (mis > 0) {
      EXPECT_EQ(j["merging_mis"], mis) << args;
      EXPECT_EQ(header.at("merging_mis"), j["merging_mis"].dump()) << args;
    } else {
      EXPECT_FALSE(j.contains("merging_mis")) << args;
      EXPECT_EQ(header.count("merging_mis"), 0u) << args;
    }
  }
}

// Checked before the scene is loaded, so no render is lost at its end to a path that cannot be written.
TEST(Cli, UnwritableOutputIsRefusedBeforeRendering) {
  std::string err;
  EXPECT_EQ(run_pathcl("render " + scene("tiny.json") + " --spp 1 -o /proc/pathcl-cannot-write.exr", &err), 2) << err;
  EXPECT_NE(err.find("-o /proc/pathcl-cannot-write.exr: cannot write into the directory /proc"), std::string::npos)
      << err;
  EXPECT_EQ(err.find("spp in"), std::string::npos) << err;  // nothing was rendered
}

TEST(Cli, DevicesInfoAndRays) {
  EXPECT_EQ(run_pathcl("devices"), 0);
  std::string err;
  EXPECT_EQ(run_pathcl("info " + scene("tiny.json"), &err), 0) << err;

  // Two rays: one down onto the floor of the box (y = 0), one into the sky.
  std::vector<RayRecord> rays = {{{0.5f, 1, 0.5f}, 0, {0, -1, 0}, INFINITY}, {{0, 1, 5}, 0, {0, 0, 1}, INFINITY}};
  std::string ray_file = temp_dir() + "/two.rays", hit_file = temp_dir() + "/two.hits";
  std::ofstream(ray_file, std::ios::binary).write(reinterpret_cast<const char*>(rays.data()), sizeof(RayRecord) * 2);
  ASSERT_EQ(run_pathcl("rays " + scene("tiny.json") + " --rays " + ray_file + " --hits " + hit_file + " --repeat 2", &err), 0)
      << err;
  std::vector<HitRecord> hits(2);
  std::ifstream(hit_file, std::ios::binary).read(reinterpret_cast<char*>(hits.data()), sizeof(HitRecord) * 2);
  EXPECT_FLOAT_EQ(hits[0].t, 1.0f);
  EXPECT_LE(hits[0].prim, 1u);  // the floor: the first quad of the first shape, as two triangles
  EXPECT_EQ(hits[1].t, INFINITY);
  EXPECT_EQ(hits[1].prim, PC_INVALID);
  // A work group the device cannot run is bad input, as for render (runtime/device.h, kernel_work_group).
  EXPECT_EQ(run_pathcl("rays " + scene("tiny.json") + " --rays " + ray_file + " --work-group 100000", &err), 2);
  EXPECT_NE(err.find("error: --work-group 100000: "), std::string::npos) << err;
  EXPECT_NE(err.find("runs the ray kernel in work groups of at most"), std::string::npos) << err;

  // A ray file whose size is not a multiple of 32 bytes is bad input.
  std::ofstream(ray_file, std::ios::binary) << "short";
  EXPECT_EQ(run_pathcl("rays " + scene("tiny.json") + " --rays " + ray_file, &err), 2);
  EXPECT_NE(err.find("multiple of the 32-byte"), std::string::npos) << err;
}

TEST(Cli, InfoDumpsTheCleanedWorldSpaceTrianglesAsObj) {
  // tiny.json: the box's 3 quads (6 triangles), an analytic sphere, an inline 2-triangle emitter.
  std::string obj = temp_dir() + "/dump/tiny.obj", err;
  ASSERT_EQ(run_pathcl("info " + scene("tiny.json") + " --dump-obj " + obj, &err), 0) << err;
  std::ifstream in(obj);
  std::string line;
  std::vector<std::string> objects, spheres;
  int vertices = 0, faces = 0;
  while (std::getline(in, line)) {
    if (line.rfind("o ", 0) == 0) objects.push_back(line);
    if (line.rfind("# sphere ", 0) == 0) spheres.push_back(line);
    vertices += line.rfind("v ", 0) == 0;
    faces += line.rfind("f ", 0) == 0;
  }
  EXPECT_EQ(objects, (std::vector<std::string>{"o shapes[0]", "o shapes[2]"}));
  EXPECT_EQ(spheres, (std::vector<std::string>{"# sphere shapes[1] 0 0.5 0 0.4 0"}));
  EXPECT_EQ(vertices, 8 + 4);
  EXPECT_EQ(faces, 6 + 2);  // the triangle count of `pathcl rays` without the sphere
}

TEST(Cli, SelfIntersectingClosedMeshIsOrientedWithAWarning) {
  // Two overlapping closed boxes in one OBJ file, inside out, emitting from their front side, with
  // "orient": true. CGAL's orient_to_bound_a_volume requires a mesh without self-intersections; each
  // box is turned outward by its signed volume instead, so the camera outside sees the emission.
  std::string out = temp_dir() + "/self-intersecting.exr", err, info;
  ASSERT_EQ(run_pathcl("render " + scene("self-intersecting-orient.json") + " -o " + out, &err), 0) << err;
  EXPECT_NE(err.find("warning: shapes[0] (meshes/overlapping-boxes.obj): the closed mesh intersects itself"),
            std::string::npos) << err;
  Image image = read_exr(out);
  size_t centre = 3 * (image.width * (image.height / 2) + image.width / 2);
  EXPECT_GE(image.rgb[centre], 1.0f);  // Le = 1 seen directly, plus what the box reflects
  ASSERT_EQ(run_pathcl("info " + scene("self-intersecting-orient.json"), &err, &info), 0) << err;
  EXPECT_NE(info.find("flipped 24 faces; closed, self-intersecting"), std::string::npos) << info;
}

TEST(Cli, FilmLargerThanTheDeviceIsAClearRuntimeFailure) {
  std::string scene_file = write_temp_file("huge.json", R"({"camera": {"position": [0,0,5], "look_at": [0,0,0],
    "width": 16384, "height": 16384}, "materials": {"m": {"type": "diffuse"}},
    "shapes": [{"type": "sphere", "radius": 1, "material": "m"}]})");
  std::string err, out = temp_dir() + "/huge.exr";
  EXPECT_EQ(run_pathcl("render " + scene_file + " --spp 1 -o " + out, &err), 1) << err;
  EXPECT_NE(err.find("MiB"), std::string::npos) << err;  // names the sizes involved
  EXPECT_FALSE(fs::exists(out));
}

// On PoCL with its own cache on, the cache holds stamps (kernel_program.cpp); with it off, binaries: both kinds.
class CliKernelCache : public ::testing::TestWithParam<const char*> {};

TEST_P(CliKernelCache, DamagedEntryIsDetectedAndRebuilt) {
  std::string cache = temp_dir() + "/kernel-cache-damage-" + GetParam(), stats = temp_dir() + "/cache.json";
  fs::remove_all(cache);
  const char* previous = std::getenv("PATHCL_KERNEL_CACHE");
  std::string saved = previous ? previous : "";
  setenv("PATHCL_KERNEL_CACHE", cache.c_str(), 1);
  const bool binaries = std::string(GetParam()) == "binaries";
  if (binaries) setenv("POCL_KERNEL_CACHE", "0", 1);
  // One lane: the smallest program (with PoCL's cache off each run generates its code again).
  std::string render = "render " + scene("tiny.json") + " --spp 1 --lanes 1 --quiet -o " + temp_dir() + "/c.exr --stats " + stats;
  auto from_cache = [&] { return nlohmann::json::parse(std::ifstream(stats))["kernel_from_cache"].get<bool>(); };
  // The cache's entries: its files but the builds' locks (kernel_program.cpp).
  auto entries = [&] {
    std::vector<fs::path> files;
    for (const auto& entry : fs::directory_iterator(cache))
      if (entry.path().extension() != ".lock") files.push_back(entry.path());
    return files;
  };
  std::string err;
  ASSERT_EQ(run_pathcl(render, &err), 0) << err;
  EXPECT_FALSE(from_cache());
  ASSERT_EQ(run_pathcl(render, &err), 0) << err;
  EXPECT_TRUE(from_cache());
  size_t damaged = 0;
  for (const fs::path& entry : entries()) {
    std::fstream f(entry, std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(std::streamoff(fs::file_size(entry) / 2));
    f.put('\x7f');
    ++damaged;
  }
  EXPECT_GT(damaged, 0u);
  ASSERT_EQ(run_pathcl(render, &err), 0) << err;  // rebuilt from source, not handed to the driver
  EXPECT_FALSE(from_cache());
  ASSERT_EQ(run_pathcl(render, &err), 0) << err;  // and stored again
  EXPECT_TRUE(from_cache());
  for (const fs::path& entry : entries())  // the kind of entry this test is about
    EXPECT_EQ(entry.extension() == ".built", is_pocl(test_device().info) && !binaries) << entry;
  if (binaries) unsetenv("POCL_KERNEL_CACHE");
  if (previous) setenv("PATHCL_KERNEL_CACHE", saved.c_str(), 1); else unsetenv("PATHCL_KERNEL_CACHE");
}
INSTANTIATE_TEST_SUITE_P(Kinds, CliKernelCache, ::testing::Values("stamps", "binaries"));

// Two processes that need the same program at once, on an empty cache: one compiles it, the other waits for
// the cache entry and loads it (MPI ranks on one machine, tests run at once, scripts).
TEST(CliKernelCacheConcurrency, TwoProcessesBuildingOneProgramCompileItOnce) {
  std::string cache = temp_dir() + "/kernel-cache-concurrent";
  fs::remove_all(cache);
  std::string render = "PATHCL_KERNEL_CACHE=" + cache + " POCL_CACHE_DIR=" + cache + "/pocl " + PATHCL_BINARY +
                       " render " + scene("tiny.json") + " --spp 1 --lanes 1 --quiet -o " + temp_dir() + "/concurrent-";
  std::string both = "(" + render + "a.exr --stats " + temp_dir() + "/concurrent-a.json & " + render + "b.exr --stats " +
                     temp_dir() + "/concurrent-b.json & wait)";
  ASSERT_EQ(std::system(both.c_str()), 0);
  int built = 0;
  for (const char* which : {"a", "b"})
    built += !nlohmann::json::parse(std::ifstream(temp_dir() + "/concurrent-" + which + ".json"))["kernel_from_cache"].get<bool>();
  EXPECT_EQ(built, 1);
}

// The command line refuses what the scene file refuses: one set of limits (scene/scene_limits.h).
TEST(Cli, OptionsHaveTheSceneFilesLimits) {
  struct Case {
    std::string args, message;
  } cases[] = {
      {"--spp 16777217", "--spp 16777217: expected an integer in [1, 16777216]"},
      {"--spp 0", "--spp 0: expected an integer in [1, 16777216]"},
      {"--spp -1", "--spp -1: expected an integer in [1, 16777216]"},
      {"--spp 3.5", "Could not convert: --spp = 3.5"},
      {"--max-depth 1025", "--max-depth 1025: expected an integer in [0, 1024]"},
      {"--max-depth -1", "--max-depth -1: expected an integer in [0, 1024]"},
      {"--seed 4294967296", "--seed 4294967296: expected an integer in [0, 4294967295]"},
      {"--pass-spp 16777217", "--pass-spp 16777217: expected an integer in [0, 16777216]"},
      {"--time nan", "--time: expected a finite number of seconds > 0"},
      {"--time inf", "--time: expected a finite number of seconds > 0"},
      {"--time 0", "--time: expected a finite number of seconds > 0"},
      {"--target-error -1", "--target-error: expected a finite relMSE > 0"},
      {"--checkpoint-every -1", "--checkpoint-every: expected a finite number of seconds >= 0"},
      {"--work-group 100000", "--work-group 100000: "},
  };
  for (const Case& c : cases) {
    std::string out = temp_dir() + "/limits.exr", err;
    EXPECT_EQ(run_pathcl("render " + scene("tiny.json") + " " + c.args + " -o " + out, &err), 2) << c.args << "\n" << err;
    EXPECT_NE(err.find("error: " + c.message), std::string::npos) << c.args << "\n" << err;
    EXPECT_FALSE(fs::exists(out)) << c.args;
  }
  std::string err, out = temp_dir() + "/limits.exr";
  EXPECT_EQ(run_pathcl("render " + scene("tiny.json") + " --spp 16777216 --time 0.05 --max-depth 1024 -o " + out, &err), 0)
      << err;
  EXPECT_EQ(run_pathcl("rays " + scene("tiny.json") + " --rays x.rays --repeat 0", &err), 2);
  EXPECT_NE(err.find("--repeat 0: expected an integer in [1, 1000000]"), std::string::npos) << err;
  for (const char* z : {"nan", "inf", "0", "-1"}) {
    EXPECT_EQ(run_pathcl("compare " + out + " " + out + " --z-threshold " + z, &err), 2) << z;
    EXPECT_NE(err.find("--z-threshold"), std::string::npos) << z << ": " << err;
  }
}

// Outputs are checked before rendering: the format comes from the extension, a directory or a second
// use of one file is refused, and nothing is written.
TEST(Cli, OutputNamesAreCheckedBeforeRendering) {
  std::string dir = temp_dir() + "/outputs";
  fs::create_directories(dir + "/a-directory");
  struct Case {
    std::string args, message;
  } cases[] = {
      {"-o " + dir + "/a-directory", "-o " + dir + "/a-directory: is a directory; expected a file name ending in .exr or .png"},
      {"-o " + dir + "/new-directory/", "-o " + dir + "/new-directory/: is a directory; expected a file name"},
      {"-o " + dir + "/img.jpg", "-o " + dir + "/img.jpg: pathcl does not write .jpg files; expected a name ending in .exr (OpenEXR) or .png"},
      {"-o " + dir + "/img", "-o " + dir + "/img: no file extension"},
      {"-o " + dir + "/a.exr --png " + dir + "/b.jpg", "--png " + dir + "/b.jpg: pathcl does not write .jpg files; expected a name ending in .png"},
      {"-o " + dir + "/a.exr --png " + dir + "/a.exr", "--png " + dir + "/a.exr: pathcl does not write .exr files"},
      {"-o " + dir + "/a.png --png " + dir + "/./a.png", "--png " + dir + "/./a.png: the same file as -o " + dir + "/a.png"},
      {"-o " + dir + "/a.exr --stats " + dir + "/a.exr", "--stats " + dir + "/a.exr: the same file as -o"},
      {"-o " + dir + "/a.exr --checkpoint " + dir + "/a.exr", "--checkpoint " + dir + "/a.exr: the same file as -o"},
      {"-o " + dir + "/a.png --variance", "--variance: the variance layer needs an EXR output"},
      {"-o " + dir + "/a.exr --stats " + dir + "/a-directory", "--stats " + dir + "/a-directory: is a directory; expected a file name"},
  };
  for (const Case& c : cases) {
    std::string err;
    EXPECT_EQ(run_pathcl("render " + scene("tiny.json") + " --spp 1 " + c.args, &err), 2) << c.args << "\n" << err;
    EXPECT_NE(err.find("error: " + c.message), std::string::npos) << c.args << "\n" << err;
    EXPECT_EQ(err.find("spp in"), std::string::npos) << c.args << "\n" << err;  // nothing was rendered
  }
  for (const auto& entry : fs::recursive_directory_iterator(dir))
    EXPECT_TRUE(entry.is_directory()) << entry.path() << " was written";

  // -o NAME.png writes a PNG, -o NAME.EXR an EXR.
  std::string err;
  ASSERT_EQ(run_pathcl("render " + scene("tiny.json") + " --spp 1 -o " + dir + "/img.png", &err), 0) << err;
  std::ifstream png(dir + "/img.png", std::ios::binary);
  char magic[8] = {};
  png.read(magic, 8);
  EXPECT_EQ(std::string(magic + 1, 3), "PNG");
  ASSERT_EQ(run_pathcl("render " + scene("tiny.json") + " --spp 1 -o " + dir + "/IMG.EXR", &err), 0) << err;
  EXPECT_EQ(read_exr(dir + "/IMG.EXR").spp, 1);
  ASSERT_EQ(run_pathcl("info " + scene("tiny.json") + " --dump-obj " + dir + "/a-directory", &err), 2) << err;
  EXPECT_NE(err.find("--dump-obj " + dir + "/a-directory: is a directory"), std::string::npos) << err;
}

// -q drops the progress bar and the summary line, never the warnings.
TEST(Cli, QuietKeepsTheWarnings) {
  // A degenerate triangle beside a real one: the clean-up removes it with a warning.
  std::string file = write_temp_file("degenerate.json", R"({"camera": {"position": [0,0,5], "look_at": [0,0,0],
    "width": 8, "height": 8}, "materials": {"m": {"type": "diffuse"}},
    "shapes": [{"type": "triangles", "positions": [[0,0,0], [1,0,0], [0,1,0], [2,2,0]],
                "indices": [[0,1,2], [0,1,1]], "material": "m", "emission": [1,1,1]}]})");
  std::string err, out = temp_dir() + "/quiet.exr";
  ASSERT_EQ(run_pathcl("render " + file + " --spp 1 -q -o " + out, &err), 0) << err;
  EXPECT_NE(err.find("warning: shapes[0]"), std::string::npos) << err;
  EXPECT_EQ(err.find("spp in"), std::string::npos) << err;
}

// An emitter whose area is 0 in float (1e-30 sides) is no light; when it was the only one, say that the
// image will be black (the scene file's own no-light warning cannot see it: the file has an emitter).
TEST(Cli, OnlyZeroAreaEmittersWarnThatTheSceneIsBlack) {
  std::string file = write_temp_file("zero-area.json", R"({"camera": {"position": [0,0,5], "look_at": [0,0,0],
    "width": 8, "height": 8}, "materials": {"m": {"type": "diffuse"}},
    "shapes": [{"type": "triangles", "positions": [[0,0,0], [1e-30,0,0], [0,1e-30,0]], "indices": [[0,1,2]],
                "material": "m", "emission": [1,1,1]}, {"type": "sphere", "radius": 1, "material": "m"}]})");
  std::string err;
  ASSERT_EQ(run_pathcl("render " + file + " --spp 1 -q -o " + temp_dir() + "/zero-area.exr", &err), 0) << err;
  EXPECT_NE(err.find("warning: 1 zero-area emitters are not lights, and the scene has no other light: it renders black"),
            std::string::npos)
      << err;
}

TEST(Cli, VersionNamesTheRevisionAndThePlatforms) {
  std::string out, err;
  ASSERT_EQ(run_pathcl("--version", &err, &out), 0) << err;
  EXPECT_EQ(out.rfind("pathcl " PATHCL_VERSION " (git ", 0), 0u) << out;
  EXPECT_NE(out.find("OpenCL platforms:\n  "), std::string::npos) << out;
  EXPECT_NE(out.find("Portable Computing Language"), std::string::npos) << out;  // PoCL, as every test machine has
}

// --device cpu and gpu select by type; a type this machine lacks is bad usage naming the type.
TEST(Cli, DevicesByType) {
  std::string devices, err, stats = temp_dir() + "/by-type.json";
  ASSERT_EQ(run_pathcl("devices", &err, &devices), 0) << err;
  ASSERT_EQ(run_pathcl("render " + scene("tiny.json") + " --spp 1 --device cpu --stats " + stats + " -o " +
                           temp_dir() + "/cpu.exr", &err),
            0)
      << err;
  nlohmann::json j = nlohmann::json::parse(std::ifstream(stats));
  EXPECT_EQ(j["devices"].size(), 1u);
  EXPECT_NE(devices.find(j["device"].get<std::string>() + " (CPU)"), std::string::npos) << devices;
  int gpu = run_pathcl("render " + scene("tiny.json") + " --spp 1 --device gpu -o " + temp_dir() + "/gpu.exr", &err);
  bool has_gpu = false;  // a GPU other than Oclgrind (an interpreter calling itself a GPU)
  std::istringstream lines(devices);
  for (std::string line; std::getline(lines, line);)
    has_gpu = has_gpu || (line.find(" (GPU)") != std::string::npos && line.find("Oclgrind") == std::string::npos);
  if (!has_gpu) {
    EXPECT_EQ(gpu, 2) << err;
    EXPECT_NE(err.find("--device gpu: no GPU device found"), std::string::npos) << err;
  } else {
    EXPECT_EQ(gpu, 0) << err;
  }
}

// Messages name the source file relative to the tree (runtime/device.cpp:118), not the build machine's path.
TEST(Cli, OpenClErrorsNameSourceFilesRelativeToTheTree) {
  try {
    CL_CHECK(CL_INVALID_VALUE);
    FAIL() << "CL_CHECK did not throw";
  } catch (const RuntimeFailure& e) {
    std::string message = e.what();
    EXPECT_NE(message.find("CL_INVALID_VALUE (-30) at tests/cli_test.cpp:"), std::string::npos) << message;
    EXPECT_EQ(message.find(PATHCL_SOURCE_DIR), std::string::npos) << message;
  }
}
