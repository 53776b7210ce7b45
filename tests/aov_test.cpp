// AOVs (kernels/aov.cl, runtime/film_layout.h): exact values on planes and through a mirror, the beauty's
// bits unchanged by them, their own bits the same for every lane width, unit split, technique and resumed
// render, and the command line's --aov and render.aovs with their EXR layers.
#include <cmath>
#include <cstring>
#include <set>

#include <gtest/gtest.h>

#include "runtime/checkpoint.h"
#include "runtime/image_io.h"
#include "test_support.h"

namespace {

// A camera at the origin looking down -z at a diffuse plane z = -2 (facing it), 16 x 16 pixels, fov 40.
const char* kPlaneScene = R"({
  "camera": {"position": [0, 0, 0], "look_at": [0, 0, -1], "fov_y_degrees": 40, "width": 16, "height": 16},
  "materials": {"wall": {"type": "diffuse", "reflectance": [0.625, 0.5, 0.25]}},
  "shapes": [
    {"type": "triangles", "positions": [[-5, -5, -2], [5, -5, -2], [5, 5, -2], [-5, 5, -2]],
     "indices": [[0, 1, 2], [0, 2, 3]], "material": "wall"},
    {"type": "sphere", "center": [0, 0, 3], "radius": 0.5, "material": "wall", "emission": [4, 4, 4]}
  ]
})";

// The camera looks down -z at a mirror tilted 45 degrees (normal (0, 1, 1) / sqrt 2): every camera ray is
// reflected up to a diffuse ceiling y = 3 facing down.
const char* kMirrorScene = R"({
  "camera": {"position": [0, 0, 0], "look_at": [0, 0, -1], "fov_y_degrees": 10, "width": 8, "height": 8},
  "materials": {"mirror": {"type": "mirror", "reflectance": [0.5, 0.75, 1]},
                "ceiling": {"type": "diffuse", "reflectance": [0.625, 0.5, 0.25]}},
  "shapes": [
    {"type": "triangles", "positions": [[-4, -4, 2], [4, -4, 2], [4, 4, -6], [-4, 4, -6]],
     "indices": [[0, 1, 2], [0, 2, 3]], "material": "mirror"},
    {"type": "triangles", "positions": [[-50, 3, -50], [50, 3, -50], [50, 3, 50], [-50, 3, 50]],
     "indices": [[0, 1, 2], [0, 2, 3]], "material": "ceiling"},
    {"type": "sphere", "center": [0, 1, 0], "radius": 0.2, "material": "ceiling", "emission": [4, 4, 4]}
  ]
})";

DeviceScene scene_from(const std::string& name, const char* json) {
  return load_device_scene(write_temp_file(name, json));
}

const uint32_t kAllAovs = (1u << PC_AOV_COUNT) - 1;

RenderOptions aov_options(uint32_t spp = 4) {
  RenderOptions o;
  o.spp = spp;
  o.max_depth = 4;
  o.aovs = kAllAovs;
  return o;
}

const Film::Aov& aov_of(const Film& f, uint32_t aov) {
  for (const Film::Aov& a : f.aovs)
    if (a.aov == aov) return a;
  throw std::logic_error("no such AOV in the film");
}

// The words of the film's AOV layers (after the technique's own).
std::vector<uint32_t> aov_words(const Film& f) {
  size_t first = f.layout.offset(f.layout.layers.size() - PC_AOV_COUNT);
  return std::vector<uint32_t>(f.words.begin() + first, f.words.end());
}

}  // namespace

// A diffuse plane: albedo its reflectance and normal its own, exactly; depth between the distances at the
// pixel's corners (the samples spread over the pixel); position on the plane; material id 1.
TEST(Aov, PlaneAgainstClosedForm) {
  DeviceScene scene = scene_from("plane.json", kPlaneScene);
  RenderResult r = render(test_device(), scene, aov_options(8));
  const Film& f = r.film;
  ASSERT_EQ(f.aovs.size(), size_t(PC_AOV_COUNT));
  const double tan_half = std::tan(20.0 * M_PI / 180);
  for (uint32_t y = 0; y < 16; ++y)
    for (uint32_t x = 0; x < 16; ++x) {
      size_t p = y * 16 + x;
      SCOPED_TRACE("pixel " + std::to_string(x) + ", " + std::to_string(y));
      const std::vector<float>& albedo = aov_of(f, PC_AOV_ALBEDO).values;
      EXPECT_EQ(albedo[3 * p], 0.625f);
      EXPECT_EQ(albedo[3 * p + 1], 0.5f);
      EXPECT_EQ(albedo[3 * p + 2], 0.25f);
      const std::vector<float>& normal = aov_of(f, PC_AOV_NORMAL).values;
      EXPECT_EQ(normal[3 * p], 0.0f);
      EXPECT_EQ(normal[3 * p + 1], 0.0f);
      EXPECT_EQ(normal[3 * p + 2], 1.0f);
      // The ray through image point (a, b) (tangent-plane coordinates) meets z = -2 at 2 sqrt(a^2 + b^2 + 1).
      double a0 = (2.0 * x / 16 - 1) * tan_half, a1 = (2.0 * (x + 1) / 16 - 1) * tan_half;
      double b0 = (1 - 2.0 * (y + 1) / 16) * tan_half, b1 = (1 - 2.0 * y / 16) * tan_half;
      auto nearest = [](double lo, double hi) { return lo <= 0 && hi >= 0 ? 0.0 : std::min(lo * lo, hi * hi); };
      double lo = 2 * std::sqrt(nearest(a0, a1) + nearest(b0, b1) + 1);
      double hi = 2 * std::sqrt(std::max(a0 * a0, a1 * a1) + std::max(b0 * b0, b1 * b1) + 1);
      float depth = aov_of(f, PC_AOV_DEPTH).values[p];
      EXPECT_GE(depth, lo * (1 - 1e-6));
      EXPECT_LE(depth, hi * (1 + 1e-6));
      const std::vector<float>& pos = aov_of(f, PC_AOV_POSITION).values;
      EXPECT_NEAR(pos[3 * p + 2], -2.0, 1e-5);
      EXPECT_GE(pos[3 * p] / 2, a0 - 1e-6);
      EXPECT_LE(pos[3 * p] / 2, a1 + 1e-6);
      EXPECT_EQ(aov_of(f, PC_AOV_MATERIAL_ID).values[p], 1.0f);
      EXPECT_EQ(aov_of(f, PC_AOV_SHAPE_ID).values[p], 1.0f);  // shapes[0]
    }
}

// Shape ids of instances are the placing shapes' (each placement its own), of the rest the shapes'
// own; escaped rays give 0.
TEST(Aov, ShapeIdsNameThePlacingShapes) {
  const std::string path = std::string(PATHCL_TEST_SCENES) + "/instances.json";
  SceneDescription description = load_scene(path);
  DeviceScene scene = load_device_scene(path);
  RenderOptions o = aov_options(1);
  o.aovs = 1u << PC_AOV_SHAPE_ID;
  Film f = render(test_device(), scene, o).film;
  std::set<uint32_t> seen(f.aovs.at(0).values.begin(), f.aovs.at(0).values.end());
  std::set<uint32_t> instances, others;
  for (size_t i = 0; i < description.shapes.size(); ++i)
    (description.shapes[i].instance_of != PC_INVALID ? instances : others).insert(uint32_t(i + 1));
  ASSERT_GE(instances.size(), 2u);
  size_t instances_seen = 0;
  for (uint32_t id : seen) {
    EXPECT_TRUE(id == 0 || instances.count(id) || others.count(id)) << id;
    instances_seen += instances.count(id);
  }
  EXPECT_GE(instances_seen, 2u) << "two placements of one mesh must have two ids";
}

// Seen through a mirror, the albedo is the mirror's reflectance times the ceiling's (products of short
// binary fractions: exact), the normal the ceiling's, and the ids and depth the mirror's.
TEST(Aov, AlbedoThroughAMirrorIsTheProductOfReflectances) {
  DeviceScene scene = scene_from("mirror.json", kMirrorScene);
  RenderResult r = render(test_device(), scene, aov_options());
  const Film& f = r.film;
  for (size_t p = 0; p < 64; ++p) {
    SCOPED_TRACE("pixel " + std::to_string(p));
    const std::vector<float>& albedo = aov_of(f, PC_AOV_ALBEDO).values;
    EXPECT_EQ(albedo[3 * p], 0.5f * 0.625f);
    EXPECT_EQ(albedo[3 * p + 1], 0.75f * 0.5f);
    EXPECT_EQ(albedo[3 * p + 2], 1.0f * 0.25f);
    const std::vector<float>& normal = aov_of(f, PC_AOV_NORMAL).values;
    EXPECT_EQ(normal[3 * p], 0.0f);
    EXPECT_EQ(normal[3 * p + 1], -1.0f);
    EXPECT_EQ(normal[3 * p + 2], 0.0f);
    EXPECT_EQ(aov_of(f, PC_AOV_MATERIAL_ID).values[p], 2.0f);  // the mirror (materials in name order: ceiling, mirror)
    EXPECT_NEAR(aov_of(f, PC_AOV_DEPTH).values[p], 2.0, 0.2);
  }
}

// The beauty is the same bits with and without AOVs, for every technique; the AOVs are the same bits for
// every technique (they follow the same camera rays), lane width and split into units.
TEST(Aov, BeautyUnchangedAndAovsTheSameEverywhere) {
  DeviceScene scene = load_device_scene(std::string(PATHCL_TEST_SCENES) + "/tiny.json");
  std::vector<uint32_t> reference_aovs;  // every AOV of the path integrator
  for (const char* technique : {"path", "light", "bdpt"}) {
    SCOPED_TRACE(technique);
    RenderOptions plain = aov_options();
    plain.aovs = 0;
    plain.integrator = technique;
    RenderResult without = render(test_device(), scene, plain);
    RenderOptions with = plain;
    with.aovs = kAllAovs;
    RenderResult r = render(test_device(), scene, with);
    size_t own = without.film.words.size();
    ASSERT_EQ(r.film.layout.offset(1), own);
    EXPECT_TRUE(std::equal(without.film.words.begin(), without.film.words.end(), r.film.words.begin()));
    EXPECT_EQ(r.film.mean, without.film.mean);
    EXPECT_EQ(r.rays, without.rays);
    std::vector<uint32_t> aovs = aov_words(r.film);
    if (reference_aovs.empty()) reference_aovs = aovs;
    EXPECT_EQ(aovs, reference_aovs);
    RenderOptions split = with;
    split.tile_pixels = 37;
    split.max_unit_pixels = 111;
    split.pass_spp = 3;
    EXPECT_EQ(aov_words(render(test_device(), scene, split).film), reference_aovs) << "split";
  }
  for (uint32_t lanes : {1u, 8u, 16u}) {
    RenderOptions o = aov_options();
    o.lanes = lanes;
    EXPECT_EQ(aov_words(render(test_device(), scene, o).film), reference_aovs) << lanes << " lanes";
  }
}

// A render resumed from a film with AOVs (a checkpoint's) gives the uninterrupted render's bits; a
// checkpoint is refused for a render with other AOVs, saying why.
TEST(Aov, ResumeAndCheckpointsCarryTheAovs) {
  DeviceScene scene = load_device_scene(std::string(PATHCL_TEST_SCENES) + "/tiny.json");
  RenderOptions o = aov_options(8);
  Film whole = render(test_device(), scene, o).film;
  RenderOptions half = aov_options(4);
  half.checkpoint = temp_dir() + "/aov.ckpt";
  half.checkpoint_key = render_key(scene, o);
  render(test_device(), scene, half);
  const Technique& path = technique_named("path", "test");
  const uint32_t pixels = scene.header.width * scene.header.height;
  Film start = read_checkpoint(half.checkpoint, half.checkpoint_key, scene.header.width, scene.header.height, path,
                               make_film_layout(path.layers, kAllAovs, pixels));
  EXPECT_EQ(start.spp, 4u);
  RenderOptions resumed = o;
  resumed.resume = &start;
  Film end = render(test_device(), scene, resumed).film;
  EXPECT_EQ(end.words, whole.words);
  try {
    read_checkpoint(half.checkpoint, half.checkpoint_key, scene.header.width, scene.header.height, path,
                    make_film_layout(path.layers, 1u << PC_AOV_ALBEDO, pixels));
    ADD_FAILURE() << "a checkpoint with other AOVs was accepted";
  } catch (const UsageError& e) {
    EXPECT_NE(std::string(e.what()).find("--aov must match"), std::string::npos) << e.what();
  }
}

// --aov writes each AOV as an EXR layer and lists them in the header; render.aovs does the same from the
// scene file; unknown names are usage errors naming the place.
TEST(Aov, CommandLineAndSceneFileWriteExrLayers) {
  std::string scene = write_temp_file("cli-plane.json", kPlaneScene);
  std::string out = temp_dir() + "/aov.exr", err;
  ASSERT_EQ(run_pathcl("render " + scene + " --spp 2 -q --aov albedo,normal,depth,material_id -o " + out, &err), 0) << err;
  Image image = read_exr(out);
  EXPECT_EQ(image.attributes["aovs"], "albedo,normal,depth,material_id");
  EXPECT_EQ(image.attributes["material_id_names"], R"(["wall"])");
  const ImageLayer* albedo = find_layer(image, "albedo");
  ASSERT_NE(albedo, nullptr);
  EXPECT_EQ(albedo->channels, (std::vector<std::string>{"R", "G", "B"}));
  EXPECT_EQ(albedo->values[0], 0.625f);
  const ImageLayer* normal = find_layer(image, "normal");
  ASSERT_NE(normal, nullptr);
  EXPECT_EQ(normal->values[2], 1.0f);
  const ImageLayer* id = find_layer(image, "material_id");
  ASSERT_NE(id, nullptr);
  EXPECT_TRUE(id->integer);
  EXPECT_EQ(id->values[0], 1.0f);
  ASSERT_NE(find_layer(image, "depth"), nullptr);
  EXPECT_EQ(find_layer(image, "position"), nullptr);

  std::string json = kPlaneScene;
  json.replace(json.rfind('}'), 1, R"(, "render": {"spp": 2, "aovs": ["uv", "position"]}})");
  std::string with_aovs = write_temp_file("cli-plane-aovs.json", json);
  std::string out2 = temp_dir() + "/aov2.exr";
  ASSERT_EQ(run_pathcl("render " + with_aovs + " -q -o " + out2, &err), 0) << err;
  Image image2 = read_exr(out2);
  EXPECT_EQ(image2.attributes["aovs"], "position,uv");
  EXPECT_NE(find_layer(image2, "uv"), nullptr);

  EXPECT_EQ(run_pathcl("render " + scene + " -q --aov albedo,glow -o " + out, &err), 2);
  EXPECT_NE(err.find("--aov: unknown AOV \"glow\""), std::string::npos) << err;
  json = kPlaneScene;
  json.replace(json.rfind('}'), 1, R"(, "render": {"aovs": ["normal", "glow"]}})");
  EXPECT_EQ(run_pathcl("render " + write_temp_file("bad-aov.json", json) + " -q -o " + out, &err), 2);
  EXPECT_NE(err.find("render.aovs[1]: unknown AOV \"glow\""), std::string::npos) << err;
  EXPECT_EQ(run_pathcl("render " + scene + " -q --aov albedo -o " + temp_dir() + "/aov.png", &err), 2);
  EXPECT_NE(err.find("--aov: the AOV layers need an EXR output"), std::string::npos) << err;
}
