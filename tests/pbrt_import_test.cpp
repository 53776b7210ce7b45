// pbrt-v4 scene files (scene/pbrt_import.cpp, docs/scene-format.md ("pbrt-v4 scenes")): small files written here give the
// expected pathcl JSON for each directive, transform form, material, light and shape the importer maps;
// approximations come with a warning naming their place, and bad or unsupported input is an error that
// names the file and line. The Cornell box in tests/scenes/pbrt imports whole.
#include <cmath>
#include <filesystem>
#include <functional>
#include <random>
#include <string>

#include <glm/mat4x4.hpp>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "scene/scene_error.h"
#include "scene/scene_import.h"
#include "test_support.h"

using nlohmann::json;

namespace {

constexpr double kPi = 3.14159265358979323846;

// A camera and film before WorldBegin: 4 lines, so that the world's first line is line 5.
const std::string kHeader =
    "LookAt 0 0 5  0 0 0  0 1 0\n"
    "Camera \"perspective\" \"float fov\" 45\n"
    "Film \"rgb\" \"integer xresolution\" 16 \"integer yresolution\" 16\n"
    "WorldBegin\n";

const std::string kTriangle = "Shape \"trianglemesh\" \"point3 P\" [0 0 0  1 0 0  0 1 0] \"integer indices\" [0 1 2]\n";

std::string pbrt_path(const std::string& name) { return temp_dir() + "/pbrt/" + name; }

ImportedScene import_file(const std::string& name, const std::string& text) {
  return import_pbrt(write_temp_file("pbrt/" + name, text), text);
}

// The message of the SceneError that importing throws ("" if it imports).
std::string import_error(const std::string& name, const std::string& text) {
  try {
    import_file(name, text);
  } catch (const SceneError& e) {
    return e.what();
  }
  return "";
}

bool has_warning(const ImportedScene& s, const std::string& prefix, const std::string& words) {
  for (const std::string& w : s.warnings)
    if (w.rfind(prefix, 0) == 0 && w.find(words) != std::string::npos) return true;
  return false;
}

std::string warnings_of(const ImportedScene& s) {
  std::string out;
  for (const std::string& w : s.warnings) out += w + "\n";
  return out;
}

std::string origin_of(const ImportedScene& s, const std::string& key) {
  for (const auto& [k, v] : s.origins)
    if (k == key) return v;
  return "";
}

// A shape's transform as a matrix (identity without one), rows as written.
glm::dmat4 matrix_of(const json& shape) {
  glm::dmat4 m(1.0);
  if (!shape.contains("transform")) return m;
  const json& rows = shape["transform"]["matrix"];
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) m[c][r] = rows[r][c].get<double>();
  return m;
}

void expect_matrix(const glm::dmat4& got, const std::vector<std::vector<double>>& rows) {
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) EXPECT_NEAR(got[c][r], rows[r][c], 1e-12) << "row " << r << " column " << c;
}

void expect_vec(const json& v, double x, double y, double z, double tolerance = 1e-12) {
  ASSERT_TRUE(v.is_array() && v.size() == 3) << v;
  EXPECT_NEAR(v[0].get<double>(), x, tolerance) << v;
  EXPECT_NEAR(v[1].get<double>(), y, tolerance) << v;
  EXPECT_NEAR(v[2].get<double>(), z, tolerance) << v;
}

}  // namespace

// ---- The camera

TEST(PbrtImport, LookAtAndFovOfAWideFilmGiveTheCameraLeftHanded) {
  const ImportedScene s = import_file("camera-wide.pbrt",
                                      "LookAt 1 2 3  1 2 0  0 1 0\n"
                                      "Camera \"perspective\" \"float fov\" 40\n"
                                      "Film \"rgb\" \"integer xresolution\" 200 \"integer yresolution\" 100\n"
                                      "WorldBegin\n" + kTriangle);
  const json& c = s.scene["camera"];
  expect_vec(c["position"], 1, 2, 3);
  expect_vec(c["look_at"], 1, 2, 2);
  expect_vec(c["up"], 0, 1, 0);
  // The shorter axis is the vertical one: fov is the vertical field of view.
  EXPECT_NEAR(c["fov_y_degrees"].get<double>(), 40, 1e-12);
  EXPECT_EQ(c["width"], 200);
  EXPECT_EQ(c["height"], 100);
  EXPECT_EQ(c["type"], "perspective");
  // pbrt's camera +x is cross(up, forward): the image's right is world -x here, pathcl's "left" frame.
  EXPECT_EQ(c["handedness"], "left");
  EXPECT_EQ(origin_of(s, "camera"), pbrt_path("camera-wide.pbrt") + ":2: Camera \"perspective\"");
}

TEST(PbrtImport, FovOfATallFilmIsHorizontal) {
  const ImportedScene s = import_file("camera-tall.pbrt",
                                      "LookAt 0 0 0  0 0 -1  0 1 0\n"
                                      "Camera \"perspective\" \"float fov\" 40\n"
                                      "Film \"rgb\" \"integer xresolution\" 100 \"integer yresolution\" 200\n"
                                      "WorldBegin\n" + kTriangle);
  double expected = 2 * std::atan(2 * std::tan(20 * kPi / 180)) * 180 / kPi;
  EXPECT_NEAR(s.scene["camera"]["fov_y_degrees"].get<double>(), expected, 1e-9);
}

TEST(PbrtImport, AMirroredCameraIsRightHandedAndATransformedOneKeepsItsFrame) {
  // Scale -1 1 1 before LookAt (as many pbrt scenes write it) gives pathcl's own frame: no handedness key.
  const ImportedScene s = import_file("camera-mirrored.pbrt",
                                      "Scale -1 1 1\nLookAt 0 1 5  0 1 0  0 1 0\nCamera \"perspective\"\n"
                                      "WorldBegin\n" + kTriangle);
  EXPECT_FALSE(s.scene["camera"].contains("handedness")) << s.scene["camera"];
  expect_vec(s.scene["camera"]["position"], 0, 1, 5);
  // The default film (1280 x 720) and fov (90, vertical on a wide film).
  EXPECT_EQ(s.scene["camera"]["width"], 1280);
  EXPECT_EQ(s.scene["camera"]["height"], 720);
  EXPECT_NEAR(s.scene["camera"]["fov_y_degrees"].get<double>(), 90, 1e-12);

  // A camera placed by Translate and Rotate: camera-from-world, so the camera sits at the inverse.
  const ImportedScene r = import_file("camera-rotated.pbrt",
                                      "Rotate 90 0 1 0\nTranslate -3 0 0\n"
                                      "Camera \"perspective\" \"float lensradius\" 0.1 \"float focaldistance\" 4\n"
                                      "WorldBegin\n" + kTriangle);
  const json& c = r.scene["camera"];
  expect_vec(c["position"], 3, 0, 0);
  // Camera +z (forward) in world space: Rotate 90 about y takes world +x to camera -z, so forward is -x.
  expect_vec(c["look_at"], 2, 0, 0);
  expect_vec(c["up"], 0, 1, 0);
  EXPECT_EQ(c["type"], "thin_lens");
  EXPECT_NEAR(c["aperture_radius"].get<double>(), 0.1, 1e-12);
  EXPECT_NEAR(c["focus_distance"].get<double>(), 4, 1e-12);
}

TEST(PbrtImport, FilmFilterSamplerAndIntegratorMapOntoRenderSettings) {
  const ImportedScene d = import_file("defaults.pbrt", "LookAt 0 0 5 0 0 0 0 1 0\nCamera \"perspective\"\nWorldBegin\n" + kTriangle);
  // pbrt-v4's defaults: zsobol 16 spp, volpath maxdepth 5, seed 0, a Gaussian filter of radius 1.5, sigma 0.5.
  EXPECT_EQ(d.scene["render"], json::parse(R"({"spp": 16, "max_depth": 5, "seed": 0, "sampler": "sobol", "integrator": "path"})"));
  EXPECT_EQ(d.scene["camera"]["filter"], json::parse(R"({"type": "gaussian", "sigma": 0.5, "radius": 1.5})"));
  EXPECT_TRUE(has_warning(d, pbrt_path("defaults.pbrt") + ": ", "subtracts the Gaussian's value at the radius")) << warnings_of(d);

  const ImportedScene s = import_file("settings.pbrt",
                                      "LookAt 0 0 5 0 0 0 0 1 0\nCamera \"perspective\"\n"
                                      "Sampler \"stratified\" \"integer xsamples\" 3 \"integer ysamples\" 5 \"integer seed\" 7\n"
                                      "Integrator \"bdpt\" \"integer maxdepth\" 12\n"
                                      "PixelFilter \"triangle\" \"float xradius\" 1.5 \"float yradius\" 1.5\n"
                                      "Film \"rgb\" \"string filename\" \"out.exr\"\n"
                                      "WorldBegin\n" + kTriangle);
  EXPECT_EQ(s.scene["render"], json::parse(R"({"spp": 15, "max_depth": 12, "seed": 7, "sampler": "stratified", "integrator": "bdpt"})"));
  EXPECT_EQ(s.scene["camera"]["filter"], json::parse(R"({"type": "tent", "radius": 1.5})"));
  EXPECT_TRUE(has_warning(s, pbrt_path("settings.pbrt") + ":6: ", "--output")) << warnings_of(s);

  const ImportedScene p = import_file("sppm.pbrt",
                                      "Option \"seed\" 3\nLookAt 0 0 5 0 0 0 0 1 0\nCamera \"perspective\"\n"
                                      "Sampler \"pmj02bn\" \"integer pixelsamples\" 4\n"
                                      "Integrator \"sppm\" \"float radius\" 0.25 \"integer photonsperiteration\" 1000\n"
                                      "PixelFilter \"box\"\nWorldBegin\n" + kTriangle);
  EXPECT_EQ(p.scene["render"], json::parse(R"({"spp": 4, "max_depth": 5, "seed": 3, "sampler": "sobol",
                                               "integrator": {"type": "sppm", "radius": 0.25}})"));
  EXPECT_EQ(p.scene["camera"]["filter"], json::parse(R"({"type": "box"})"));
  EXPECT_TRUE(has_warning(p, pbrt_path("sppm.pbrt") + ":4: ", "sobol")) << warnings_of(p);
  EXPECT_TRUE(has_warning(p, pbrt_path("sppm.pbrt") + ":5: ", "photonsperiteration")) << warnings_of(p);
  EXPECT_TRUE(p.warnings.size() == 2) << warnings_of(p);  // the box filter of radius 0.5 is exact

  // pbrt-v4's mlt: mutationsperpixel is the image's spp; maxdepth beyond pathcl's mlt's 16 is clamped.
  const ImportedScene m = import_file("mlt.pbrt",
                                      "LookAt 0 0 5 0 0 0 0 1 0\nCamera \"perspective\"\n"
                                      "Integrator \"mlt\" \"integer maxdepth\" 20 \"integer mutationsperpixel\" 300 "
                                      "\"float largestepprobability\" 0.25 \"integer chains\" 500 \"integer bootstrapsamples\" 5000\n"
                                      "PixelFilter \"box\"\nWorldBegin\n" + kTriangle);
  EXPECT_EQ(m.scene["render"], json::parse(R"({"spp": 300, "max_depth": 16, "seed": 0, "sampler": "sobol",
                                               "integrator": {"type": "mlt", "bootstrap": 5000, "large_step": 0.25,
                                                              "mutation_size": 0.01}})"));
  EXPECT_TRUE(has_warning(m, pbrt_path("mlt.pbrt") + ":3: ", "maxdepth 20 is beyond pathcl's largest for mlt, 16")) << warnings_of(m);
  EXPECT_TRUE(has_warning(m, pbrt_path("mlt.pbrt") + ":3: ", "chains ignored")) << warnings_of(m);
  EXPECT_TRUE(has_warning(m, pbrt_path("mlt.pbrt") + ":3: ", "Kelemen's exponential moves")) << warnings_of(m);
}

// ---- Transforms

TEST(PbrtImport, TransformDirectivesComposeAsPbrtDoes) {
  const std::string w = kHeader;
  // CTM = T(1,2,3) R(90 about z) S(2): the rows of T R S.
  const ImportedScene a = import_file("trs.pbrt", w + "Translate 1 2 3\nRotate 90 0 0 1\nScale 2 2 2\n" + kTriangle);
  expect_matrix(matrix_of(a.scene["shapes"][0]), {{0, -2, 0, 1}, {2, 0, 0, 2}, {0, 0, 2, 3}, {0, 0, 0, 1}});
  // ConcatTransform post-multiplies a matrix given column by column (the translation last).
  const ImportedScene b = import_file("concat.pbrt", w + "Translate 1 2 3\nConcatTransform [1 0 0 0  0 1 0 0  0 0 1 0  5 6 7 1]\n"
                                                         "ConcatTransform [0 1 0 0  -1 0 0 0  0 0 1 0  0 0 0 1]\n" + kTriangle);
  expect_matrix(matrix_of(b.scene["shapes"][0]), {{0, -1, 0, 6}, {1, 0, 0, 8}, {0, 0, 1, 10}, {0, 0, 0, 1}});
  // Transform replaces the CTM; Identity resets it.
  const ImportedScene c = import_file("replace.pbrt", w + "Translate 9 9 9\nTransform [2 0 0 0  0 3 0 0  0 0 4 0  1 1 1 1]\n" +
                                                          kTriangle + "Identity\n" + kTriangle);
  expect_matrix(matrix_of(c.scene["shapes"][0]), {{2, 0, 0, 1}, {0, 3, 0, 1}, {0, 0, 4, 1}, {0, 0, 0, 1}});
  EXPECT_FALSE(c.scene["shapes"][1].contains("transform"));
  // CoordinateSystem and CoordSysTransform.
  const ImportedScene d = import_file("coordsys.pbrt", w + "Translate 0 5 0\nCoordinateSystem \"up5\"\nIdentity\nScale 3 3 3\n"
                                                           "CoordSysTransform \"up5\"\n" + kTriangle);
  expect_matrix(matrix_of(d.scene["shapes"][0]), {{1, 0, 0, 0}, {0, 1, 0, 5}, {0, 0, 1, 0}, {0, 0, 0, 1}});
}

TEST(PbrtImport, AttributeBeginEndScopesTransformMaterialAndOrientation) {
  const ImportedScene s = import_file("scope.pbrt", kHeader +
                                                        "Material \"diffuse\" \"rgb reflectance\" [0.1 0.2 0.3]\n"
                                                        "AttributeBegin\n"
                                                        "  Translate 0 0 4\n"
                                                        "  Material \"diffuse\" \"rgb reflectance\" [0.9 0.8 0.7]\n"
                                                        "  ReverseOrientation\n" +
                                                        "  " + kTriangle +
                                                        "AttributeEnd\n" + kTriangle);
  const json& shapes = s.scene["shapes"];
  ASSERT_EQ(shapes.size(), 2u);
  expect_matrix(matrix_of(shapes[0]), {{1, 0, 0, 0}, {0, 1, 0, 0}, {0, 0, 1, 4}, {0, 0, 0, 1}});
  EXPECT_FALSE(shapes[1].contains("transform"));
  EXPECT_EQ(s.scene["materials"][shapes[0]["material"].get<std::string>()]["reflectance"], json::parse("[0.9, 0.8, 0.7]"));
  EXPECT_EQ(s.scene["materials"][shapes[1]["material"].get<std::string>()]["reflectance"], json::parse("[0.1, 0.2, 0.3]"));
  // ReverseOrientation inside the block turns the first triangle over (pathcl's front side is its winding).
  EXPECT_EQ(shapes[0]["indices"], json::parse("[[0, 2, 1]]"));
  EXPECT_EQ(shapes[1]["indices"], json::parse("[[0, 1, 2]]"));
  EXPECT_EQ(origin_of(s, "shapes[0]"), pbrt_path("scope.pbrt") + ":10: Shape \"trianglemesh\"");
  EXPECT_EQ(origin_of(s, "materials." + shapes[1]["material"].get<std::string>()),
            pbrt_path("scope.pbrt") + ":5: Material \"diffuse\"");
}

TEST(PbrtImport, AttributeSetsDefaultParametersThatAShapeOverrides) {
  const ImportedScene s = import_file("attribute.pbrt", kHeader +
                                                            "AttributeBegin\n"
                                                            "  Attribute \"shape\" \"float radius\" 0.25\n"
                                                            "  Shape \"sphere\"\n"
                                                            "  Shape \"sphere\" \"float radius\" 2\n"
                                                            "AttributeEnd\n"
                                                            "Shape \"sphere\"\n");
  EXPECT_EQ(s.scene["shapes"][0]["radius"], 0.25);
  EXPECT_EQ(s.scene["shapes"][1]["radius"], 2);
  EXPECT_EQ(s.scene["shapes"][2]["radius"], 1);
}

// ---- Materials

TEST(PbrtImport, NamedMaterialsKeepTheirNamesAndMayBeDefinedAfterUse) {
  const ImportedScene s = import_file("named.pbrt", kHeader +
                                                        "NamedMaterial \"red\"\n" + kTriangle +
                                                        "MakeNamedMaterial \"red\" \"string type\" \"diffuse\" \"rgb reflectance\" [0.8 0.1 0.1]\n"
                                                        "MakeNamedMaterial \"unused\" \"string type\" \"diffuse\"\n");
  EXPECT_EQ(s.scene["shapes"][0]["material"], "red");
  EXPECT_EQ(s.scene["materials"]["red"], json::parse(R"({"type": "diffuse", "reflectance": [0.8, 0.1, 0.1]})"));
  EXPECT_FALSE(s.scene["materials"].contains("unused"));
  EXPECT_TRUE(has_warning(s, pbrt_path("named.pbrt") + ":8: ", "\"unused\" is used by no shape")) << warnings_of(s);
  EXPECT_EQ(origin_of(s, "materials.red"), pbrt_path("named.pbrt") + ":7: MakeNamedMaterial \"red\"");
  // pbrt-v4's default material is a grey diffuse one.
  const ImportedScene d = import_file("default-material.pbrt", kHeader + kTriangle);
  EXPECT_EQ(d.scene["materials"]["default"], json::parse(R"({"type": "diffuse", "reflectance": [0.5, 0.5, 0.5]})"));
}

TEST(PbrtImport, MaterialsMapOntoPathclsOwn) {
  const ImportedScene s = import_file(
      "materials.pbrt",
      kHeader +
          "MakeNamedMaterial \"rough\" \"string type\" \"conductor\" \"rgb eta\" [0.2 0.9 1.1] \"rgb k\" [3.9 2.4 2.1] \"float roughness\" 0.0625\n"
          "MakeNamedMaterial \"polished\" \"string type\" \"conductor\" \"rgb eta\" [2 2 2] \"rgb k\" [1 1 1]\n"
          "MakeNamedMaterial \"gold\" \"string type\" \"conductor\" \"rgb reflectance\" [0.9 0.7 0.3] \"float roughness\" 0.01 "
          "\"bool remaproughness\" false\n"
          "MakeNamedMaterial \"glass\" \"string type\" \"dielectric\" \"spectrum eta\" \"glass-BK7\"\n"
          "MakeNamedMaterial \"water\" \"string type\" \"dielectric\" \"float eta\" 1.33\n"
          "MakeNamedMaterial \"paint\" \"string type\" \"coateddiffuse\" \"rgb reflectance\" [0.2 0.3 0.4] \"float roughness\" 0.01\n"
          "MakeNamedMaterial \"spectral\" \"string type\" \"diffuse\" \"spectrum reflectance\" [300 0.5 800 0.5]\n"
          "MakeNamedMaterial \"rough glass\" \"string type\" \"dielectric\" \"float roughness\" 0.3\n"
          "MakeNamedMaterial \"pane\" \"string type\" \"thindielectric\" \"float eta\" 1.52\n"
          "MakeNamedMaterial \"chrome\" \"string type\" \"conductor\" \"rgb reflectance\" [0.8 0.5 1]\n"
          "NamedMaterial \"rough\"\n" + kTriangle + "NamedMaterial \"polished\"\n" + kTriangle + "NamedMaterial \"gold\"\n" + kTriangle +
          "NamedMaterial \"glass\"\n" + kTriangle + "NamedMaterial \"water\"\n" + kTriangle + "NamedMaterial \"paint\"\n" + kTriangle +
          "NamedMaterial \"spectral\"\n" + kTriangle + "NamedMaterial \"rough glass\"\n" + kTriangle +
          "NamedMaterial \"pane\"\n" + kTriangle + "NamedMaterial \"chrome\"\n" + kTriangle);
  const json& m = s.scene["materials"];
  const std::string file = pbrt_path("materials.pbrt");
  // Roughness r: pbrt's alpha = sqrt(r) (remapped), pathcl's roughness = sqrt(alpha).
  EXPECT_EQ(m["rough"]["type"], "rough_conductor");
  EXPECT_NEAR(m["rough"]["roughness"].get<double>(), 0.5, 1e-12);
  EXPECT_EQ(m["rough"]["eta"], json::parse("[0.2, 0.9, 1.1]"));
  EXPECT_EQ(m["rough"]["k"], json::parse("[3.9, 2.4, 2.1]"));
  // A smooth conductor is a mirror with the conductor's Fresnel term: its eta and k; of a reflectance r,
  // pbrt-v4's eta 1, k = 2 sqrt(r / (1 - r)) (r at most 0.9999).
  EXPECT_EQ(m["polished"], json::parse(R"({"type": "mirror", "eta": [2, 2, 2], "k": [1, 1, 1]})"));
  EXPECT_FALSE(has_warning(s, file + ":6: ", "")) << warnings_of(s);
  EXPECT_EQ(m["chrome"]["type"], "mirror");
  expect_vec(m["chrome"]["eta"], 1, 1, 1);
  expect_vec(m["chrome"]["k"], 2 * std::sqrt(0.8 / 0.2), 2.0, 2 * std::sqrt(0.9999 / 0.0001), 1e-9);
  EXPECT_EQ(m["pane"], json::parse(R"({"type": "thin_dielectric", "ior": 1.52})"));
  // remaproughness false: alpha is the roughness itself.
  EXPECT_EQ(m["gold"], json::parse(R"({"type": "rough_conductor", "specular": [0.9, 0.7, 0.3], "roughness": 0.1})"));
  // N-BK7 at 550 nm from SCHOTT's Sellmeier coefficients; dispersion dropped with a warning.
  EXPECT_EQ(m["glass"]["type"], "dielectric");
  EXPECT_NEAR(m["glass"]["ior"].get<double>(), 1.51852, 1e-5);
  EXPECT_TRUE(has_warning(s, file + ":8: ", "dispersion")) << warnings_of(s);
  EXPECT_EQ(m["water"], json::parse(R"({"type": "dielectric", "ior": 1.33})"));
  EXPECT_EQ(m["paint"]["type"], "plastic");
  EXPECT_EQ(m["paint"]["diffuse"], json::parse("[0.2, 0.3, 0.4]"));
  EXPECT_EQ(m["paint"]["ior"], 1.5);
  EXPECT_NEAR(m["paint"]["roughness"].get<double>(), std::sqrt(0.1), 1e-12);
  EXPECT_TRUE(has_warning(s, file + ":10: ", "plastic")) << warnings_of(s);
  // A constant reflectance spectrum is that grey in sRGB.
  expect_vec(m["spectral"]["reflectance"], 0.5, 0.5, 0.5, 2e-3);
  EXPECT_EQ(m["rough glass"]["type"], "dielectric");
  EXPECT_TRUE(has_warning(s, file + ":12: ", "rendered smooth")) << warnings_of(s);
}

TEST(PbrtImport, CheckerboardsKeepPbrtsParity) {
  const ImportedScene s = import_file(
      "checker.pbrt", kHeader +
                          "Texture \"c\" \"spectrum\" \"checkerboard\" \"rgb tex1\" [0.7 0.6 0.5] \"rgb tex2\" [0.1 0.2 0.3]\n"
                          "  \"float uscale\" 4 \"float vscale\" 3 \"float udelta\" 0.3 \"float vdelta\" -0.7\n"
                          "Material \"diffuse\" \"texture reflectance\" \"c\"\n" + kTriangle);
  const json& c = s.scene["materials"]["diffuse@checker.pbrt:7"]["reflectance"]["checkerboard"];
  ASSERT_TRUE(c.is_object()) << s.scene["materials"];
  expect_vec(c["color0"], 0.7, 0.6, 0.5);
  expect_vec(c["color1"], 0.1, 0.2, 0.3);
  EXPECT_TRUE(has_warning(s, pbrt_path("checker.pbrt") + ":5: ", "footprint")) << warnings_of(s);
  // pathcl's rule (docs/scene-format.md, kernels/texture.cl) with the emitted tiles and offset gives pbrt-v4's
  // tex1 where floor(uscale u + udelta) + floor(vscale v + vdelta) is even, at points off the tiles' edges.
  const double tu = c["tiles"][0], tv = c["tiles"][1], ou = c["offset"][0], ov = c["offset"][1];
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> uniform(-2, 3);
  for (int i = 0; i < 1000; ++i) {
    const double u = uniform(rng), v = uniform(rng);
    const double s_ = 4 * u + 0.3, t_ = 3 * v - 0.7;
    if (std::abs(s_ - std::round(s_)) < 1e-6 || std::abs(t_ - std::round(t_)) < 1e-6) continue;
    const bool pbrt_tex1 = (int64_t(std::floor(s_)) + int64_t(std::floor(t_))) % 2 == 0;
    const bool pathcl_color0 = (int64_t(std::floor(u * tu + ou)) + int64_t(std::floor((1 - v) * tv + ov))) % 2 == 0;
    ASSERT_EQ(pbrt_tex1, pathcl_color0) << "u " << u << " v " << v;
  }
}

TEST(PbrtImport, ImageTexturesAndAlphaBecomePathclTexturesAndOpacity) {
  write_temp_png("pbrt/textures/wood.png", 2, 2, std::vector<unsigned char>(12, 200));
  write_temp_png("pbrt/textures/mask.png", 2, 2, std::vector<unsigned char>(12, 255));
  const ImportedScene s = import_file(
      "textures.pbrt",
      kHeader +
          "Texture \"wood\" \"spectrum\" \"imagemap\" \"string filename\" \"textures/wood.png\" \"string wrap\" \"clamp\"\n"
          "Texture \"mask\" \"float\" \"imagemap\" \"string filename\" \"textures/mask.png\"\n"
          "Material \"diffuse\" \"texture reflectance\" \"wood\"\n" + kTriangle +
          "Shape \"trianglemesh\" \"point3 P\" [0 0 0 1 0 0 0 1 0] \"point2 uv\" [0 0 1 0 0 1] \"float alpha\" 0.5\n"
          "Shape \"trianglemesh\" \"point3 P\" [0 0 0 1 0 0 0 1 0] \"point2 uv\" [0 0 1 0 0 1] \"texture alpha\" \"mask\"\n");
  const json& shapes = s.scene["shapes"];
  const json& m = s.scene["materials"];
  std::string base = shapes[0]["material"];
  EXPECT_EQ(m[base]["reflectance"], json::parse(R"({"texture": "textures/wood.png", "wrap": "clamp"})"));
  // A mesh without uvs under a texture gets pbrt's default uvs, (0,0) (1,0) (1,1) at the corners.
  EXPECT_EQ(shapes[0]["uvs"], json::parse("[[0, 0], [1, 0], [1, 1]]"));
  // "alpha" is the material's opacity, in a variant of the material.
  EXPECT_EQ(m[shapes[1]["material"].get<std::string>()]["opacity"], 0.5);
  EXPECT_EQ(m[shapes[2]["material"].get<std::string>()]["opacity"], json::parse(R"({"texture": "textures/mask.png", "wrap": "repeat"})"));
  EXPECT_EQ(m[shapes[1]["material"].get<std::string>()]["reflectance"], m[base]["reflectance"]);
}

// ---- Shapes and lights

TEST(PbrtImport, AnAreaLightSourceMakesItsShapesEmit) {
  const ImportedScene s = import_file("area.pbrt", kHeader +
                                                       "AttributeBegin\n"
                                                       "  AreaLightSource \"diffuse\" \"rgb L\" [4 3 2] \"float scale\" 2 \"bool twosided\" true\n"
                                                       "  Translate 0 3 0\n"
                                                       "  Shape \"sphere\" \"float radius\" 0.5\n"
                                                       "AttributeEnd\n"
                                                       "Shape \"sphere\"\n"
                                                       "AttributeBegin\n"
                                                       "  AreaLightSource \"diffuse\" \"rgb L\" [1 1 1] \"float power\" 100\n"
                                                       "  Shape \"bilinearmesh\" \"point3 P\" [0 0 0  2 0 0  0 2 0  2 2 0]\n"
                                                       "AttributeEnd\n");
  const json& shapes = s.scene["shapes"];
  ASSERT_EQ(shapes.size(), 3u);
  EXPECT_EQ(shapes[0]["type"], "sphere");
  EXPECT_EQ(shapes[0]["radius"], 0.5);
  EXPECT_EQ(shapes[0]["emission"], json::parse("[8, 6, 4]"));
  EXPECT_EQ(shapes[0]["two_sided"], true);
  glm::dmat4 m = matrix_of(shapes[0]);
  EXPECT_NEAR(m[3][1], 3, 1e-12);
  EXPECT_FALSE(shapes[1].contains("emission"));
  // A bilinear patch (p00 p10 p01 p11) is two triangles wound like cross(p10 - p00, p01 - p00); "power" over
  // its area, one-sided: L = power / (pi area).
  EXPECT_EQ(shapes[2]["positions"], json::parse("[[0, 0, 0], [2, 0, 0], [0, 2, 0], [2, 2, 0]]"));
  EXPECT_EQ(shapes[2]["indices"], json::parse("[[0, 1, 3], [0, 3, 2]]"));
  expect_vec(shapes[2]["emission"], 100 / (4 * kPi), 100 / (4 * kPi), 100 / (4 * kPi));
  EXPECT_EQ(origin_of(s, "shapes[0]"), pbrt_path("area.pbrt") + ":8: Shape \"sphere\"");
}

TEST(PbrtImport, LightSourcesMapOntoPathclLights) {
  const ImportedScene s = import_file(
      "lights.pbrt",
      kHeader +
          "LightSource \"point\" \"point3 from\" [1 2 3] \"rgb I\" [1 2 3] \"float scale\" 2\n"
          "AttributeBegin\n"
          "  Translate 0 10 0\n"
          "  LightSource \"spot\" \"point3 from\" [0 0 0] \"point3 to\" [0 -1 0] \"float coneangle\" 40 \"float conedeltaangle\" 10\n"
          "AttributeEnd\n"
          "LightSource \"distant\" \"point3 from\" [0 1 0] \"point3 to\" [0 0 0] \"rgb L\" [3 3 3]\n"
          "LightSource \"infinite\" \"rgb L\" [0.5 0.25 0.125]\n"
          "LightSource \"point\" \"float power\" 100\n");
  const json& l = s.scene["lights"];
  ASSERT_EQ(l.size(), 5u) << l;
  EXPECT_EQ(l[0], json::parse(R"({"type": "point", "position": [1, 2, 3], "intensity": [2, 4, 6]})"));
  EXPECT_EQ(l[1]["type"], "spot");
  expect_vec(l[1]["position"], 0, 10, 0);
  expect_vec(l[1]["direction"], 0, -1, 0);
  EXPECT_EQ(l[1]["outer_angle_degrees"], 40);
  EXPECT_EQ(l[1]["inner_angle_degrees"], 30);
  expect_vec(l[1]["intensity"], 1, 1, 1);
  // Light travels from "from" to "to".
  EXPECT_EQ(l[2], json::parse(R"({"type": "directional", "direction": [0, -1, 0], "irradiance": [3, 3, 3]})"));
  EXPECT_EQ(l[3], json::parse(R"({"type": "environment", "radiance": [0.5, 0.25, 0.125]})"));
  // "power" of a point light: I = power / (4 pi).
  expect_vec(l[4]["intensity"], 100 / (4 * kPi), 100 / (4 * kPi), 100 / (4 * kPi));
  EXPECT_EQ(origin_of(s, "lights[1]"), pbrt_path("lights.pbrt") + ":8: LightSource \"spot\"");
}

namespace {

// A minimal uncompressed OpenEXR file of float R, G, B (grey: value(x, y) at column x of row y), with a
// "chromaticities" attribute when `chromaticities` has 8 numbers (red, green, blue, white x and y): written
// byte by byte, as pathcl's own EXR writer takes no chromaticities.
std::string write_temp_exr(const std::string& name, int width, int height, const std::function<float(int, int)>& value,
                           const std::vector<float>& chromaticities = {}) {
  std::string out;
  auto bytes = [&](const void* p, size_t n) { out.append(static_cast<const char*>(p), n); };
  auto i32 = [&](int32_t v) { bytes(&v, 4); };
  auto f32 = [&](float v) { bytes(&v, 4); };
  auto attribute = [&](const std::string& attr, const std::string& type, int32_t size) {
    out += attr + '\0' + type + '\0';
    i32(size);
  };
  out += "\x76\x2f\x31\x01";
  i32(2);  // version 2, single-part scanlines
  attribute("channels", "chlist", 3 * 18 + 1);
  for (const char* c : {"B", "G", "R"}) {
    out += std::string(c) + '\0';
    i32(2);  // FLOAT
    i32(0);  // pLinear and reserved
    i32(1);
    i32(1);
  }
  out += '\0';
  attribute("compression", "compression", 1);
  out += '\0';
  for (const char* window : {"dataWindow", "displayWindow"}) {
    attribute(window, "box2i", 16);
    i32(0), i32(0), i32(width - 1), i32(height - 1);
  }
  attribute("lineOrder", "lineOrder", 1);
  out += '\0';
  attribute("pixelAspectRatio", "float", 4);
  f32(1);
  attribute("screenWindowCenter", "v2f", 8);
  f32(0), f32(0);
  attribute("screenWindowWidth", "float", 4);
  f32(1);
  if (chromaticities.size() == 8) {
    attribute("chromaticities", "chromaticities", 32);
    for (float c : chromaticities) f32(c);
  }
  out += '\0';
  const uint64_t first = out.size() + 8 * size_t(height), line = 8 + 12 * size_t(width);
  for (int y = 0; y < height; ++y) {
    uint64_t offset = first + y * line;
    bytes(&offset, 8);
  }
  for (int y = 0; y < height; ++y) {
    i32(y);
    i32(12 * width);
    for (int c = 0; c < 3; ++c)
      for (int x = 0; x < width; ++x) f32(value(x, y));
  }
  return write_temp_file("pbrt/" + name, out);
}

std::string write_temp_exr(const std::string& name, int width, int height, float value,
                           const std::vector<float>& chromaticities = {}) {
  return write_temp_exr(name, width, height, [value](int, int) { return value; }, chromaticities);
}

bool has_light_warning(const ImportedScene& s) {
  for (const std::string& w : s.warnings)
    if (w.find("LightSource") != std::string::npos) return true;
  return false;
}

// The 3 x 3 part of an environment's transform, identity without one.
glm::dmat3 rotation_of(const json& light) { return glm::dmat3(matrix_of(light)); }

}  // namespace

TEST(PbrtImport, AnImageInfiniteLightIsAnEqualAreaEnvironmentAtTheNearestTexel) {
  write_temp_exr("sky.exr", 16, 16, 0.5f);
  // pbrt's usual placement of a sky: Rotate -90 1 0 0 takes light space's +z (the square's centre) to +y.
  const ImportedScene s = import_file("sky.pbrt", kHeader +
                                                      "AttributeBegin\n"
                                                      "  Rotate -90 1 0 0\n"
                                                      "  LightSource \"infinite\" \"string filename\" \"sky.exr\" \"float scale\" 2.5\n"
                                                      "AttributeEnd\n");
  EXPECT_FALSE(has_light_warning(s)) << warnings_of(s);
  const json& l = s.scene["lights"];
  ASSERT_EQ(l.size(), 1u) << l;
  EXPECT_EQ(l[0]["type"], "environment");
  EXPECT_EQ(l[0]["file"], "sky.exr");
  EXPECT_EQ(l[0]["mapping"], "equal_area");
  EXPECT_EQ(l[0]["filter"], "nearest");
  EXPECT_EQ(l[0]["scale"], 2.5);
  // The map's direction d is the light-space direction: world = CTM d.
  expect_matrix(matrix_of(l[0]), {{1, 0, 0, 0}, {0, 0, 1, 0}, {0, -1, 0, 0}, {0, 0, 0, 1}});
  EXPECT_LT(glm::length(rotation_of(l[0]) * glm::dvec3(0, 0, 1) - glm::dvec3(0, 1, 0)), 1e-15);
  EXPECT_EQ(origin_of(s, "lights[0]"), pbrt_path("sky.pbrt") + ":7: LightSource \"infinite\"");
  // It loads: an equal-area map at the nearest texel, placed by the rotation.
  const DeviceScene scene = load_device_scene(pbrt_path("sky.pbrt"));
  ASSERT_EQ(scene.lights.size(), 1u);
  EXPECT_EQ(scene.lights[0].slot, PC_ENV_EQUAL_AREA_NEAREST);
  EXPECT_EQ(scene.lights[0].emission.x, 2.5f);

  // A translation and a uniform scale change no direction (pbrt normalises the light-space direction): the
  // rotation alone; without one, no transform at all.
  const ImportedScene moved = import_file(
      "moved-sky.pbrt", kHeader + "Translate 1 2 3\nScale 2 2 2\nRotate 30 0 0 1\nLightSource \"infinite\" \"string filename\" \"sky.exr\"\n");
  const double c = std::cos(kPi / 6), sn = std::sin(kPi / 6);
  expect_matrix(matrix_of(moved.scene["lights"][0]), {{c, -sn, 0, 0}, {sn, c, 0, 0}, {0, 0, 1, 0}, {0, 0, 0, 1}});
  EXPECT_EQ(moved.scene["lights"][0]["scale"], 1);
  const ImportedScene plain = import_file("plain-sky.pbrt", kHeader + "LightSource \"infinite\" \"string filename\" \"sky.exr\"\n");
  EXPECT_FALSE(plain.scene["lights"][0].contains("transform"));

  // A portal is dropped with a warning, as before.
  const ImportedScene portal = import_file(
      "portal-sky.pbrt", kHeader + "LightSource \"infinite\" \"string filename\" \"sky.exr\"\n"
                                   "  \"point3 portal\" [0 0 0  1 0 0  1 1 0  0 1 0]\n");
  EXPECT_TRUE(has_warning(portal, pbrt_path("portal-sky.pbrt") + ":6: ", "the portal is dropped")) << warnings_of(portal);
  EXPECT_EQ(portal.scene["lights"][0]["mapping"], "equal_area");
}

TEST(PbrtImport, AnImageLightsIlluminanceIsPbrtsUpperHemisphereEstimate) {
  // pbrt-v4 scales the map by E / k, k = 2 pi / (w h) x the sum of luminance x cos theta over the texels whose
  // centre is above the horizon: z = 1 - r^2 > 0 at the centre, r = |u'| + |v'| < 1 (u' = 2u - 1, v' = 2v - 1).
  // A map of 1 above the horizon and 7 below: only the upper texels count; for 64 x 64 texels their sum
  // comes to about pi / 2 (half the texels, cos theta 1/2 on average).
  const int n = 64;
  auto upper = [&](int x, int y) { return std::abs(2 * (x + 0.5) / n - 1) + std::abs(2 * (y + 0.5) / n - 1) < 1; };
  double sum = 0;
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) {
      double r = std::abs(2 * (x + 0.5) / n - 1) + std::abs(2 * (y + 0.5) / n - 1);
      if (upper(x, y)) sum += 1 - r * r;
    }
  const double k = sum * 2 * kPi / (n * n);
  EXPECT_NEAR(k, kPi / 2, 2e-3);
  write_temp_exr("half.exr", n, n, [&](int x, int y) { return upper(x, y) ? 1.0f : 7.0f; });
  const ImportedScene s = import_file(
      "illuminance.pbrt", kHeader + "LightSource \"infinite\" \"string filename\" \"half.exr\" \"float illuminance\" 3 \"float scale\" 2\n");
  // The luminance of grey 1 is the sum of sRGB's luminance row, 1 within 1e-12.
  EXPECT_NEAR(s.scene["lights"][0]["scale"].get<double>(), 2 * 3 / k, 1e-9);
  write_temp_exr("seven.exr", n, n, 7.0f);
  const ImportedScene sevens = import_file(
      "illuminance-7.pbrt", kHeader + "LightSource \"infinite\" \"string filename\" \"seven.exr\" \"float illuminance\" 3\n");
  EXPECT_NEAR(sevens.scene["lights"][0]["scale"].get<double>(), 3 / (7 * k), 1e-9);
}

TEST(PbrtImport, ImageLightsThatPathclCannotRenderAreRefused) {
  write_temp_exr("sky.exr", 16, 16, 0.5f);
  write_temp_exr("wide.exr", 16, 8, 0.5f);
  write_temp_exr("black.exr", 8, 8, 0.0f);
  // Rec. 2020 primaries with D65 white; and chromaticities pbrt knows no colour space of.
  write_temp_exr("rec2020.exr", 8, 8, 0.5f, {0.708f, 0.292f, 0.170f, 0.797f, 0.131f, 0.046f, 0.3127f, 0.3290f});
  write_temp_exr("odd.exr", 8, 8, 0.5f, {0.6f, 0.3f, 0.3f, 0.6f, 0.15f, 0.06f, 0.3127f, 0.3290f});
  write_temp_exr("srgb.exr", 8, 8, 0.5f, {0.64f, 0.33f, 0.3f, 0.6f, 0.15f, 0.06f, 0.3127f, 0.329f});
  const std::string sky = "LightSource \"infinite\" \"string filename\" \"sky.exr\"\n";
  struct Case {
    const char* name;
    std::string text;
    int line;
    std::vector<std::string> words;
  };
  const std::vector<Case> cases = {
      {"both.pbrt", kHeader + "LightSource \"infinite\" \"string filename\" \"sky.exr\"\n  \"rgb L\" [1 1 1]\n", 6,
       {"\"L\" and \"filename\" together"}},
      {"missing.pbrt", kHeader + "LightSource \"infinite\" \"string filename\" \"nowhere.exr\"\n", 5, {"cannot find \"nowhere.exr\""}},
      {"shear.pbrt", kHeader + "Scale 1 2 1\n" + sky, 6, {"scales unevenly or shears"}},
      {"mirror.pbrt", kHeader + "Scale -1 1 1\n" + sky, 6, {"mirrors"}},
      {"two.pbrt", kHeader + "LightSource \"infinite\" \"rgb L\" [1 1 1]\n" + sky, 6, {"a second environment light", "two.pbrt:5"}},
      {"two-images.pbrt", kHeader + sky + "LightSource \"infinite\" \"rgb L\" [1 1 1]\n", 6, {"a second environment light"}},
      {"rec2020.pbrt", kHeader + "LightSource \"infinite\" \"string filename\" \"rec2020.exr\"\n", 5, {"rec2020 colour space"}},
      {"black.pbrt", kHeader + "LightSource \"infinite\" \"string filename\" \"black.exr\" \"float illuminance\" 5\n", 5,
       {"black above the horizon"}},
      {"wide-illuminance.pbrt", kHeader + "LightSource \"infinite\" \"string filename\" \"wide.exr\" \"float illuminance\" 5\n", 5,
       {"16 x 8 texels, not square"}},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    const std::string error = import_error(c.name, c.text);
    const std::string prefix = pbrt_path(c.name) + ":" + std::to_string(c.line) + ": ";
    EXPECT_EQ(error.rfind(prefix, 0), 0u) << error;
    for (const std::string& w : c.words) EXPECT_NE(error.find(w), std::string::npos) << error << "\nmissing: " << w;
  }
  // A map that is not square imports, and the loader refuses it at the LightSource's line, naming the file.
  import_file("wide.pbrt", kHeader + "LightSource \"infinite\" \"string filename\" \"wide.exr\"\n");
  const std::string error = scene_load_error(pbrt_path("wide.pbrt"));
  EXPECT_EQ(error.rfind(pbrt_path("wide.pbrt") + ":5: ", 0), 0u) << error;
  EXPECT_NE(error.find("wide.exr is 16 x 8 texels: an equal_area map is a square image"), std::string::npos) << error;
  // sRGB's chromaticities are fine; unknown ones are sRGB to pbrt, with a warning.
  EXPECT_FALSE(has_light_warning(import_file("srgb.pbrt", kHeader + "LightSource \"infinite\" \"string filename\" \"srgb.exr\"\n")));
  const ImportedScene odd = import_file("odd.pbrt", kHeader + "LightSource \"infinite\" \"string filename\" \"odd.exr\"\n");
  EXPECT_TRUE(has_warning(odd, pbrt_path("odd.pbrt") + ":5: ", "taken as sRGB")) << warnings_of(odd);
}

TEST(PbrtImport, ObjectInstancesPlaceTheObjectsShapes) {
  const ImportedScene s = import_file("instances.pbrt", kHeader +
                                                            "ObjectBegin \"thing\"\n"
                                                            "  Translate 0 0 1\n"
                                                            "  " + kTriangle +
                                                            "ObjectEnd\n"
                                                            "AttributeBegin\n"
                                                            "  Translate 10 0 0\n"
                                                            "  ObjectInstance \"thing\"\n"
                                                            "AttributeEnd\n"
                                                            "Scale 2 2 2\n"
                                                            "ObjectInstance \"thing\"\n");
  const json& shapes = s.scene["shapes"];
  ASSERT_EQ(shapes.size(), 2u);
  // The instance's CTM times the shape's CTM inside the object.
  expect_matrix(matrix_of(shapes[0]), {{1, 0, 0, 10}, {0, 1, 0, 0}, {0, 0, 1, 1}, {0, 0, 0, 1}});
  expect_matrix(matrix_of(shapes[1]), {{2, 0, 0, 0}, {0, 2, 0, 0}, {0, 0, 2, 2}, {0, 0, 0, 1}});
  EXPECT_EQ(shapes[0]["positions"], shapes[1]["positions"]);
  EXPECT_NE(origin_of(s, "shapes[0]").find(pbrt_path("instances.pbrt") + ":11: ObjectInstance \"thing\""), std::string::npos);
}

TEST(PbrtImport, MeshNormalsBilinearPatchesAndTessellatedShapes) {
  const ImportedScene s = import_file(
      "meshes.pbrt",
      kHeader +
          // Normals facing away from the winding: pbrt takes the front side from them.
          "Shape \"trianglemesh\" \"point3 P\" [0 0 0 1 0 0 0 1 0] \"normal N\" [0 0 -1 0 0 -1 0 0 -1]\n"
          // Normals that vary: pathcl generates smooth ones.
          "Shape \"trianglemesh\" \"point3 P\" [0 0 0 1 0 0 0 1 0] \"normal N\" [0 0 1 0.3 0 1 0 0.3 1]\n"
          "Shape \"disk\" \"float radius\" 2\n"
          "Shape \"cylinder\"\n");
  const json& shapes = s.scene["shapes"];
  const std::string file = pbrt_path("meshes.pbrt");
  EXPECT_EQ(shapes[0]["indices"], json::parse("[[0, 2, 1]]"));
  EXPECT_FALSE(shapes[0].contains("smooth"));
  EXPECT_EQ(shapes[1]["smooth"], true);
  EXPECT_TRUE(has_warning(s, file + ":6: ", "smooth normals")) << warnings_of(s);
  EXPECT_EQ(shapes[2]["type"], "triangles");
  EXPECT_EQ(shapes[2]["indices"].size(), 128u);
  EXPECT_TRUE(has_warning(s, file + ":7: ", "tessellated")) << warnings_of(s);
  EXPECT_EQ(shapes[3]["smooth"], true);
  EXPECT_EQ(shapes[3]["indices"].size(), 256u);
}

TEST(PbrtImport, IncludedFilesResolvePathsAgainstTheMainFile) {
  write_temp_file("pbrt/include/meshes/main.ply", "ply\nformat ascii 1.0\nelement vertex 0\nend_header\n");
  write_temp_file("pbrt/include/sub/local.ply", "ply\nformat ascii 1.0\nelement vertex 0\nend_header\n");
  // Inside sub/: "meshes/main.ply" is relative to the main file's directory (pbrt-v4's rule), "local.ply"
  // exists only beside the included file and is taken from there, rebased, with a warning.
  write_temp_file("pbrt/include/sub/geometry.pbrt",
                  "Shape \"plymesh\" \"string filename\" \"meshes/main.ply\"\n"
                  "Shape \"plymesh\" \"string filename\" \"local.ply\"\n"
                  "Shape \"plymesh\" \"string filename\" \"missing.ply\"\n");
  const std::string error = import_error("include/scene.pbrt", kHeader + "Include \"sub/geometry.pbrt\"\n");
  EXPECT_EQ(error.rfind(pbrt_path("include/sub/geometry.pbrt") + ":3: Shape \"plymesh\": cannot find \"missing.ply\"", 0), 0u) << error;

  write_temp_file("pbrt/include/sub/geometry.pbrt",
                  "Shape \"plymesh\" \"string filename\" \"meshes/main.ply\"\n"
                  "Shape \"plymesh\" \"string filename\" \"local.ply\"\n");
  const ImportedScene s = import_file("include/scene.pbrt", kHeader + "Include \"sub/geometry.pbrt\"\n" + kTriangle);
  const json& shapes = s.scene["shapes"];
  ASSERT_EQ(shapes.size(), 3u);
  EXPECT_EQ(shapes[0]["file"], "meshes/main.ply");
  EXPECT_EQ(shapes[1]["file"], "sub/local.ply");
  EXPECT_TRUE(has_warning(s, pbrt_path("include/sub/geometry.pbrt") + ":2: ", "taken from there")) << warnings_of(s);
  EXPECT_EQ(origin_of(s, "shapes[1]"), pbrt_path("include/sub/geometry.pbrt") + ":2: Shape \"plymesh\"");
  EXPECT_EQ(origin_of(s, "shapes[2]"), pbrt_path("include/scene.pbrt") + ":6: Shape \"trianglemesh\"");
}

TEST(PbrtImport, ImportKeepsItsGraphicsStateToItself) {
  write_temp_file("pbrt/import/part.pbrt", "Translate 0 0 7\nMaterial \"diffuse\" \"rgb reflectance\" [1 0 0]\n" + kTriangle +
                                               "MakeNamedMaterial \"shared\" \"string type\" \"diffuse\"\n");
  const ImportedScene s = import_file("import/scene.pbrt", kHeader + "Import \"part.pbrt\"\nNamedMaterial \"shared\"\n" + kTriangle);
  const json& shapes = s.scene["shapes"];
  ASSERT_EQ(shapes.size(), 2u);
  EXPECT_NEAR(matrix_of(shapes[0])[3][2], 7, 1e-12);
  EXPECT_FALSE(shapes[1].contains("transform"));
  EXPECT_EQ(shapes[1]["material"], "shared");
}

TEST(PbrtImport, UnknownParametersAndApproximationsAreWarnings) {
  const ImportedScene s = import_file("warnings.pbrt", kHeader +
                                                           "Option \"disablepixeljitter\" true\n"
                                                           "Shape \"sphere\" \"float radius\" 1\n"
                                                           "    \"float colour\" 3\n"
                                                           "Material \"diffuse\" \"string normalmap\" \"n.png\"\n" + kTriangle);
  const std::string file = pbrt_path("warnings.pbrt");
  EXPECT_TRUE(has_warning(s, file + ":5: ", "Option \"disablepixeljitter\"")) << warnings_of(s);
  EXPECT_TRUE(has_warning(s, file + ":7: ", "unknown parameter \"float colour\"")) << warnings_of(s);
  EXPECT_TRUE(has_warning(s, file + ":8: ", "normal map \"n.png\" dropped")) << warnings_of(s);
}

// ---- Errors: FILE:LINE: what is wrong and what was expected

TEST(PbrtImport, ErrorsNameTheFileAndLine) {
  struct Case {
    const char* name;
    std::string text;
    int line;
    std::vector<std::string> words;
  };
  const std::vector<Case> cases = {
      {"syntax.pbrt", kHeader + "Translate 1 2\nShape \"sphere\"\n", 6, {"expected a number", "Translate takes 3 numbers", "Shape"}},
      {"unterminated.pbrt", kHeader + "Shape \"sphere\" \"float radius 1\n", 5, {"unterminated string"}},
      {"directive.pbrt", kHeader + "\n# a comment\nShapes \"sphere\"\n", 7, {"unknown directive \"Shapes\""}},
      {"material.pbrt", kHeader + "Material \"velvet\"\n", 5, {"unknown material type \"velvet\"", "coateddiffuse"}},
      {"unsupported.pbrt", kHeader + "Material \"hair\"\n" + kTriangle, 5, {"Material \"hair\" is not supported", "supported: diffuse"}},
      {"include.pbrt", kHeader + "Include \"nowhere/geometry.pbrt\"\n", 5, {"Include: cannot find \"nowhere/geometry.pbrt\""}},
      {"wrong-type.pbrt", "LookAt 0 0 5  0 0 0  0 1 0\nCamera \"perspective\"\n  \"integer fov\" 45\nWorldBegin\n", 3,
       {"\"integer fov\"", "takes \"float fov\""}},
      {"value-type.pbrt", kHeader + "Shape \"sphere\" \"float radius\" \"big\"\n", 5, {"\"float radius\": expected numbers, got a string"}},
      {"integer.pbrt", kHeader + "Shape \"trianglemesh\" \"point3 P\" [0 0 0 1 0 0 0 1 0]\n\"integer indices\" [0 1 2.5]\n", 6,
       {"expected integers, got 2.5"}},
      {"bracket.pbrt", kHeader + "Shape \"trianglemesh\" \"point3 P\" [0 0 0 1 0 0 0 1 0\n", 5, {"] closing the values"}},
      {"index.pbrt", kHeader + "Shape \"trianglemesh\" \"point3 P\" [0 0 0 1 0 0 0 1 0] \"integer indices\" [0 1 3]\n", 5,
       {"index 3 is out of range (3 positions)"}},
      {"named.pbrt", kHeader + "NamedMaterial \"nothing\"\n" + kTriangle, 5, {"NamedMaterial \"nothing\"", "no MakeNamedMaterial"}},
      {"world.pbrt", kHeader + "Camera \"perspective\"\n", 5, {"Camera belongs before WorldBegin"}},
      {"attribute.pbrt", kHeader + "AttributeBegin\n" + kTriangle, 5, {"AttributeBegin without AttributeEnd"}},
      {"medium.pbrt", kHeader + "MakeNamedMedium \"fog\" \"string type\" \"homogeneous\"\nMediumInterface \"fog\" \"\"\n" + kTriangle, 7,
       {"participating media are not supported", "\"fog\""}},
      {"camera.pbrt", "Camera \"orthographic\"\nWorldBegin\n", 1, {"Camera \"orthographic\" is not supported"}},
      {"partial.pbrt", kHeader + "Shape \"sphere\" \"float zmax\" 0.5\n", 5, {"partial sphere"}},
      {"ellipsoid.pbrt", kHeader + "Scale 1 2 1\nShape \"sphere\"\n", 6, {"ellipsoid"}},
      {"colorspace.pbrt", "ColorSpace \"aces2065-1\"\n" + kHeader, 1, {"ColorSpace \"aces2065-1\" is not supported"}},
      {"reflectance.pbrt", kHeader + "Material \"diffuse\" \"rgb reflectance\" [1.5 0 0]\n" + kTriangle, 5, {"component > 1"}},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    const std::string error = import_error(c.name, c.text);
    const std::string prefix = pbrt_path(c.name) + ":" + std::to_string(c.line) + ": ";
    EXPECT_EQ(error.rfind(prefix, 0), 0u) << error;
    for (const std::string& w : c.words) EXPECT_NE(error.find(w), std::string::npos) << error << "\nmissing: " << w;
  }
  // A file without a world block.
  EXPECT_EQ(import_error("no-world.pbrt", "Camera \"perspective\"\n"),
            pbrt_path("no-world.pbrt") + ": the file ends before WorldBegin (a pbrt scene needs a world block)");
}

// ---- A whole scene

TEST(PbrtImport, TheCornellBoxImports) {
  const std::string path = std::string(PATHCL_TEST_SCENES) + "/pbrt/cornell-box.pbrt";
  const ImportedScene s = import_pbrt(path, read_text_file(path));
  EXPECT_TRUE(s.warnings.empty()) << warnings_of(s);
  const json& scene = s.scene;
  EXPECT_EQ(scene["camera"]["width"], 64);
  EXPECT_EQ(scene["camera"]["height"], 64);
  EXPECT_FALSE(scene["camera"].contains("handedness"));  // Scale -1 1 1: pathcl's own frame
  EXPECT_EQ(scene["shapes"].size(), 8u);
  EXPECT_EQ(scene["materials"].size(), 5u);
  EXPECT_EQ(scene["render"]["max_depth"], 8);
  // The lamp, and the red wall's spectrum as a red colour.
  EXPECT_EQ(scene["shapes"][5]["emission"], json::parse("[17, 12, 4]"));
  const json& red = scene["materials"]["red"]["reflectance"];
  EXPECT_GT(red[0].get<double>(), 3 * red[1].get<double>()) << red;
  EXPECT_EQ(scene["shapes"][6]["file"], "meshes/cube.ply");
  EXPECT_EQ(scene["materials"]["metal"]["type"], "rough_conductor");
  EXPECT_EQ(origin_of(s, "shapes[5]"), path + ":38: Shape \"bilinearmesh\"");
}
