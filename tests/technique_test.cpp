// Techniques (runtime/technique.h): a technique registered from this file alone, with a kernel of its own
// (two phases and a buffer kept between them), renders through the whole engine (schedule, units, several
// film layers, AOVs beside it, checkpoints' key); the registry refuses taken names and names its
// techniques in errors.
#include <cstring>

#include <gtest/gtest.h>

#include "runtime/checkpoint.h"
#include "runtime/kernel_sources.h"
#include "runtime/technique.h"
#include "test_support.h"

namespace {

// Two phases and a buffer of the technique's own between them: `weigh`, two work items per pixel (a phase's
// own item count), leaves 0.5 and 0.25 (p % 2) for pixel p in `weights`, one each; `add` adds their sum per
// sample to the film's first word and 1 to the second. The pixel's mean is their quotient, whatever the
// split into units; without weigh's second items it would be 0.5 for every pixel.
const char* kConstantKernel = R"(
#include "shared/types.h"
#include "scene.cl"
__kernel void weigh(PC_SCENE_PARAMS, __global float* weights, uint pixel_begin, uint pixel_count, uint pixel_stride,
                    uint sample_begin, uint sample_count) {
  uint i = get_global_id(0);
  if (i >= 2u * pixel_count) return;
  uint p = pixel_begin + i / 2u * pixel_stride;
  weights[2u * p + i % 2u] = i % 2u == 0u ? 0.5f : 0.25f * (float)(p % 2u);
}
__kernel void add(PC_SCENE_PARAMS, __global float* film, __global UnitStats* stats, __global const float* weights,
                  uint pixel_begin, uint pixel_count, uint pixel_stride, uint sample_begin, uint sample_count) {
  uint i = get_global_id(0);
  if (i >= pixel_count) return;
  uint p = pixel_begin + i * pixel_stride;
  for (uint s = sample_begin; s < sample_begin + sample_count; ++s) {
    film[2u * p] += weights[2u * p] + weights[2u * p + 1u];
    film[2u * p + 1u] += 1.0f;
  }
  if (i == 0u) atomic_add(&stats->rays_lo, 1u);
}
)";

const Technique& constant_technique() {
  static const bool registered = [] {
    register_kernel_source("test_constant.cl", kConstantKernel);
    Technique t;
    t.name = "test-constant";
    t.id = 1000;
    t.summary = "test only: a constant per pixel";
    t.kernel_file = "test_constant.cl";
    t.phases = {{"weigh", "weigh", {"weights", "unit"}, [](uint32_t count, uint32_t, uint32_t) { return 2 * size_t(count); }},
                {"add", "add", {"film", "stats", "weights", "unit"}, {}}};
    t.buffers = {{"weights", [](const TechniqueSizes& s) { return 2 * s.pixels * sizeof(float); }}};
    t.layers = {{"constant", PC_LAYER_ORDERED, 2}};
    t.develop = [](Film& f, const LightTransportHeader&, uint64_t*) {
      size_t pixels = size_t(f.width) * f.height;
      f.mean.assign(3 * pixels, 0.0f);
      f.variance.assign(3 * pixels, 0.0f);
      for (size_t p = 0; p < pixels; ++p) {
        float words[2];
        std::memcpy(words, f.layer(0) + 2 * p, sizeof words);
        for (int c = 0; c < 3; ++c) f.mean[3 * p + c] = words[1] > 0 ? words[0] / words[1] : 0.0f;
      }
      f.even_mean = f.odd_mean = f.mean;
    };
    register_technique(t);
    return true;
  }();
  (void)registered;
  return technique_named("test-constant", "test");
}

}  // namespace

TEST(Technique, ATestTechniqueRendersThroughTheEngine) {
  const Technique& t = constant_technique();
  EXPECT_NE(technique_list().find("test-constant"), std::string::npos);
  DeviceScene scene = load_device_scene(std::string(PATHCL_TEST_SCENES) + "/tiny.json");
  RenderOptions o;
  o.spp = 6;
  o.integrator = t.name;
  o.aovs = 1u << PC_AOV_ALBEDO;
  o.tile_pixels = 37;
  o.pass_spp = 2;
  RenderResult r = render(test_device(), scene, o);
  ASSERT_EQ(r.film.layout.names(), "constant,albedo");
  EXPECT_EQ(r.film.spp, 6u);
  const size_t pixels = size_t(scene.header.width) * scene.header.height;
  for (size_t p = 0; p < pixels; ++p) {
    EXPECT_EQ(r.film.mean[3 * p], p % 2 ? 0.75f : 0.5f) << p;
    float count;
    std::memcpy(&count, r.film.layer(0) + 2 * p + 1, sizeof count);
    EXPECT_EQ(count, 6.0f) << p;
  }
  EXPECT_GT(r.rays, 0u);  // its counters come back
  ASSERT_EQ(r.phases.size(), 3u);  // named and timed
  EXPECT_EQ(r.phases[0].name, "weigh");
  EXPECT_EQ(r.phases[1].name, "add");
  EXPECT_EQ(r.phases[2].name, "aov");
  // The albedo beside it is the path integrator's.
  RenderOptions path = o;
  path.integrator = "path";
  Film p = render(test_device(), scene, path).film;
  EXPECT_EQ(r.film.aovs.at(0).values, p.aovs.at(0).values);
  // Its id keys checkpoints apart from path's.
  EXPECT_NE(render_key(scene, o), render_key(scene, path));
}

TEST(Technique, RegistryRefusesTakenNamesAndNamesItsTechniques) {
  constant_technique();
  Technique t = path_technique();
  EXPECT_THROW(register_technique(t), std::logic_error);
  try {
    technique_named("lite", "scene.json: render.integrator");
    ADD_FAILURE();
  } catch (const UsageError& e) {
    EXPECT_EQ(std::string(e.what()).rfind("scene.json: render.integrator: unknown integrator \"lite\" (expected path, light, bdpt, vcm, bpm, sppm, instant_radiosity, radiosity, mlt or test-constant)", 0), 0u) << e.what();
  }
  RenderOptions o;
  o.integrator = "mlt";
  o.lanes = 8;
  EXPECT_THROW(check_technique_options(technique_named("mlt", "test"), o), UsageError);
  for (const char* name : {"light", "bdpt", "vcm", "bpm", "sppm"}) {
    o.integrator = name;
    EXPECT_NO_THROW(check_technique_options(technique_named(name, "test"), o)) << name;
  }
  o.integrator = "bdpt";
  o.lanes = 0;
  o.max_depth = 1025;
  EXPECT_THROW(check_technique_options(technique_named("bdpt", "test"), o), UsageError);
}

// A technique's own options: render.integrator as {"type": NAME, OPTION: VALUE}; an option it does not
// have, or a value it does not take, is an error naming the place.
TEST(Technique, OptionsOfItsOwnAreCheckedByIt) {
  RenderOptions o;
  apply_technique_options(technique_named("path", "test"), R"({"lanes": 8})", "s.json: render.integrator", o);
  EXPECT_EQ(o.lanes, 8u);
  auto message = [&](const char* technique, const char* json) {
    try {
      apply_technique_options(technique_named(technique, "test"), json, "s.json: render.integrator", o);
    } catch (const UsageError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_EQ(message("path", R"({"lanes": 3})"), "s.json: render.integrator.lanes: expected 1, 8 or 16 (paths per work item; the same pixels), got 3");
  EXPECT_EQ(message("mlt", R"({"lanes": 8})"),
            "s.json: render.integrator.lanes: the mlt integrator has no option \"lanes\" (it has bootstrap, large_step, mutation_size)");
  EXPECT_EQ(message("light", R"({"lanes": 3})"),
            "s.json: render.integrator.lanes: expected 1, 8 or 16 (light paths per work item; the same pixels), got 3");
  EXPECT_EQ(message("path", R"({"radius": 1})"), "s.json: render.integrator.radius: the path integrator has no option \"radius\" (it has lanes)");
  // The merging integrators' radius, alpha and (vcm) merge, a boolean, and merge_mis, merging's factor in
  // vcm's MIS weights (bpm and sppm weigh nothing against their merges).
  apply_technique_options(technique_named("vcm", "test"), R"({"radius": 0.5, "alpha": 0.5, "merge": false, "merge_mis": 0.5})",
                          "s.json: render.integrator", o);
  EXPECT_EQ(o.radius, 0.5);
  EXPECT_EQ(o.alpha, 0.5);
  EXPECT_FALSE(o.merge);
  EXPECT_EQ(o.merge_mis, 0.5);
  EXPECT_EQ(message("vcm", R"({"alpha": 1.5})"), "s.json: render.integrator.alpha: expected a number in (0, 1], got 1.5");
  EXPECT_EQ(message("vcm", R"({"merge_mis": 0})"),
            "s.json: render.integrator.merge_mis: expected a number in (0, 1] (merging's factor in the MIS weights), got 0");
  EXPECT_EQ(message("bpm", R"({"merge_mis": 1})"),
            "s.json: render.integrator.merge_mis: the bpm integrator has no option \"merge_mis\" (it has lanes, radius, alpha)");
  EXPECT_EQ(message("sppm", R"({"radius": 0})"), "s.json: render.integrator.radius: expected a radius > 0 (scene units), got 0");
  EXPECT_EQ(message("vcm", R"({"merge": "no"})"), "s.json: render.integrator.merge: expected true or false, got \"no\"");
  EXPECT_EQ(message("sppm", R"({"merge": false})"),
            "s.json: render.integrator.merge: the sppm integrator has no option \"merge\" (it has lanes, radius, alpha)");
  // The gathering integrators' light paths per iteration, instant radiosity's clamp, radiosity's final gather.
  apply_technique_options(technique_named("instant_radiosity", "test"), R"({"light_paths": 32, "clamp": 2.5})",
                          "s.json: render.integrator", o);
  EXPECT_EQ(o.light_paths, 32u);
  EXPECT_EQ(o.clamp, 2.5);
  apply_technique_options(technique_named("radiosity", "test"), R"({"light_paths": 100000, "final_gather": false})",
                          "s.json: render.integrator", o);
  EXPECT_EQ(o.light_paths, 100000u);
  EXPECT_FALSE(o.final_gather);
  EXPECT_EQ(message("instant_radiosity", R"({"light_paths": 100000})"),
            "s.json: render.integrator.light_paths: expected a whole number of light paths per iteration, 1 to 65536, got 100000");
  EXPECT_EQ(message("radiosity", R"({"light_paths": 2.5})"),
            "s.json: render.integrator.light_paths: expected a whole number of light paths per iteration, 1 to 16777216, got 2.5");
  EXPECT_EQ(message("instant_radiosity", R"({"clamp": -1})"),
            "s.json: render.integrator.clamp: expected a number >= 0 (the largest geometry term cos cos / d^2, in 1 / scene units^2; 0: none), got -1");
  apply_technique_options(technique_named("mlt", "test"), R"({"bootstrap": 1000, "large_step": 0.5, "mutation_size": 0.1})",
                          "s.json: render.integrator", o);
  EXPECT_EQ(o.bootstrap, 1000u);
  EXPECT_EQ(o.large_step, 0.5);
  EXPECT_EQ(o.mutation_size, 0.1);
  EXPECT_EQ(message("mlt", R"({"large_step": 2})"), "s.json: render.integrator.large_step: expected a probability in [0, 1], got 2");
  EXPECT_EQ(message("mlt", R"({"bootstrap": 0})"),
            "s.json: render.integrator.bootstrap: expected a whole number of bootstrap states per depth, 1 to 1048576, got 0");
  EXPECT_EQ(message("mlt", R"({"mutation_size": 0})"),
            "s.json: render.integrator.mutation_size: expected a number in (0, 1] (the largest move of a small step), got 0");
  EXPECT_EQ(message("radiosity", R"({"clamp": 1})"),
            "s.json: render.integrator.clamp: the radiosity integrator has no option \"clamp\" (it has light_paths, final_gather)");

  // Through the scene file and the command line (whose --lanes overrides the scene's).
  std::string scene = read_text_file(std::string(PATHCL_TEST_SCENES) + "/tiny.json"), err;
  scene.replace(scene.find("../../scenes/"), 13, std::string(PATHCL_SOURCE_DIR) + "/scenes/");
  scene.replace(scene.find(R"("render": {)"), 11, R"("render": {"integrator": {"type": "path", "lanes": 8}, )");
  std::string path = write_temp_file("lanes.json", scene), dir = temp_dir();
  ASSERT_EQ(run_pathcl("render " + path + " -q -o " + dir + "/l.exr --stats " + dir + "/l.json", &err), 0) << err;
  EXPECT_NE(read_text_file(dir + "/l.json").find("\"lanes\": 8"), std::string::npos);
  ASSERT_EQ(run_pathcl("render " + path + " -q --lanes 1 -o " + dir + "/l.exr --stats " + dir + "/l.json", &err), 0) << err;
  EXPECT_NE(read_text_file(dir + "/l.json").find("\"lanes\": 1"), std::string::npos);
  scene.replace(scene.find(R"("type": "path", "lanes": 8)"), 26, R"("type": "mlt", "lanes": 8)");
  EXPECT_EQ(run_pathcl("render " + write_temp_file("bad.json", scene) + " -q -o " + dir + "/b.exr", &err), 2);
  EXPECT_NE(err.find("bad.json: render.integrator.lanes: the mlt integrator has no option \"lanes\""), std::string::npos) << err;
}
