// Imported scenes end to end (scene/scene_import.h): `pathcl render` and `pathcl info` on Mitsuba and pbrt
// files, `pathcl convert` (its JSON renders the same bits), errors and warnings at their source lines, and
// the two peers' image orientations, which differ: an object on the world's +x side appears on the right
// of a Mitsuba image and on the left of a pbrt image seen by the same LookAt (pbrt's camera frame is
// left-handed). The importers' parameter mappings have their own tests (mitsuba_import_test,
// pbrt_import_test); their agreement with Mitsuba's renders is scripts/bench/import-peers'.
#include <gtest/gtest.h>

#include <fstream>
#include <string>

#include "runtime/image_io.h"
#include "test_support.h"

namespace {

// A red sphere on the world's +x side and a white one on -x, lit by a point light from the camera's side.
const char kMitsubaSpheres[] = R"(<scene version="3.0.0">
  <sensor type="perspective">
    <float name="fov" value="40"/>
    <transform name="to_world"><lookat origin="0, 0, 6" target="0, 0, 0" up="0, 1, 0"/></transform>
    <sampler type="independent"><integer name="sample_count" value="4"/></sampler>
    <film type="hdrfilm"><integer name="width" value="32"/><integer name="height" value="16"/>
      <rfilter type="box"/></film>
  </sensor>
  <integrator type="path"><integer name="max_depth" value="3"/></integrator>
  <shape type="sphere"><point name="center" x="1.2" y="0" z="0"/><float name="radius" value="0.8"/>
    <bsdf type="diffuse"><rgb name="reflectance" value="0.8, 0.05, 0.05"/></bsdf></shape>
  <shape type="sphere"><point name="center" x="-1.2" y="0" z="0"/><float name="radius" value="0.8"/>
    <bsdf type="diffuse"><rgb name="reflectance" value="0.8, 0.8, 0.8"/></bsdf></shape>
  <emitter type="point"><point name="position" x="0" y="0" z="6"/><rgb name="intensity" value="40, 40, 40"/></emitter>
</scene>
)";

const char kPbrtSpheres[] = R"(# The same two spheres and light for pbrt.
LookAt 0 0 6  0 0 0  0 1 0
Camera "perspective" "float fov" [ 20 ]
Sampler "independent" "integer pixelsamples" [ 4 ]
Integrator "path" "integer maxdepth" [ 2 ]
PixelFilter "box"
Film "rgb" "integer xresolution" [ 32 ] "integer yresolution" [ 16 ]
WorldBegin
LightSource "point" "point3 from" [ 0 0 6 ] "rgb I" [ 40 40 40 ]
AttributeBegin
  Material "diffuse" "rgb reflectance" [ 0.8 0.05 0.05 ]
  Translate 1.2 0 0
  Shape "sphere" "float radius" 0.8
AttributeEnd
AttributeBegin
  Material "diffuse" "rgb reflectance" [ 0.8 0.8 0.8 ]
  Translate -1.2 0 0
  Shape "sphere" "float radius" 0.8
AttributeEnd
)";

// Red minus green summed over the left and the right half of the image.
struct Halves {
  double left = 0, right = 0;
};
Halves redness(const Image& image) {
  Halves h;
  for (uint32_t y = 0; y < image.height; ++y)
    for (uint32_t x = 0; x < image.width; ++x) {
      const float* p = &image.rgb[3 * (size_t(y) * image.width + x)];
      (x < image.width / 2 ? h.left : h.right) += p[0] - p[1];
    }
  return h;
}

Image render(const std::string& scene, const std::string& name, const std::string& options = "") {
  const std::string out = temp_dir() + "/" + name + ".exr";
  std::string err;
  EXPECT_EQ(run_pathcl("render " + scene + " -q -o " + out + " " + options, &err), 0) << err;
  return read_exr(out);
}

}  // namespace

TEST(ImportRender, MitsubaShowsPlusXOnTheRightAndPbrtOnTheLeft) {
  const Halves mitsuba = redness(render(write_temp_file("spheres.xml", kMitsubaSpheres), "spheres-xml"));
  EXPECT_GT(mitsuba.right, 10 * std::max(mitsuba.left, 1e-3)) << mitsuba.left << " " << mitsuba.right;
  const Halves pbrt = redness(render(write_temp_file("spheres.pbrt", kPbrtSpheres), "spheres-pbrt"));
  EXPECT_GT(pbrt.left, 10 * std::max(pbrt.right, 1e-3)) << pbrt.left << " " << pbrt.right;
}

TEST(ImportRender, ConvertedScenesRenderTheSameBits) {
  // Each file and the JSON convert writes for it, in another directory (paths rebased): the same pixels.
  for (const std::string& source : {std::string(PATHCL_TEST_SCENES) + "/mitsuba/cbox.xml",
                                    std::string(PATHCL_TEST_SCENES) + "/pbrt/cornell-box.pbrt",
                                    write_temp_file("spheres.pbrt", kPbrtSpheres)}) {
    SCOPED_TRACE(source);
    const std::string json = temp_dir() + "/converted/scene.json";
    std::string err;
    ASSERT_EQ(run_pathcl("convert " + source + " -q -o " + json, &err), 0) << err;
    const Image a = render(source, "source", "--spp 2 --max-depth 3"), b = render(json, "json", "--spp 2 --max-depth 3");
    ASSERT_EQ(a.rgb.size(), b.rgb.size());
    EXPECT_EQ(a.rgb, b.rgb);
  }
}

TEST(ImportRender, BadInputIsPlacedAtItsSourceLine) {
  std::string err;
  // A plugin the importer refuses, at its line; exit 2, nothing written.
  const std::string xml = write_temp_file("bad.xml", "<scene version=\"3.0.0\">\n  <shape type=\"sphere\">\n"
                                          "    <bsdf type=\"hair\"/>\n  </shape>\n</scene>\n");
  EXPECT_EQ(run_pathcl("render " + xml + " -q -o " + temp_dir() + "/bad.exr", &err), 2);
  EXPECT_NE(err.find("bad.xml:3:"), std::string::npos) << err;
  EXPECT_FALSE(std::ifstream(temp_dir() + "/bad.exr").good());
  // A value the JSON checks refuse after the translation: named at the line of the pbrt entry it came from.
  const std::string pbrt = write_temp_file("bad.pbrt", "LookAt 0 0 5 0 0 0 0 1 0\nCamera \"perspective\"\n"
                                           "WorldBegin\nLightSource \"point\" \"rgb I\" [1 1 1]\n"
                                           "Shape \"sphere\" \"float radius\" [ -1 ]\n");
  EXPECT_EQ(run_pathcl("info " + pbrt, &err), 2);
  EXPECT_NE(err.find("bad.pbrt:5:"), std::string::npos) << err;
  // convert refuses a JSON scene (it is one already) and writing over its input.
  EXPECT_EQ(run_pathcl("convert " + std::string(PATHCL_SOURCE_DIR) + "/scenes/cornell-box.json -o " +
                       temp_dir() + "/c.json", &err), 2);
  EXPECT_NE(err.find("is a pathcl JSON scene already"), std::string::npos) << err;
  EXPECT_EQ(run_pathcl("convert " + pbrt + " -o " + pbrt, &err), 2);
}

TEST(ImportRender, DefinesSetAMitsubaScenesDefaults) {
  // -D NAME=VALUE wins over the file's <default>, as Mitsuba's; a $name without either is an error at its line.
  std::string scene = kMitsubaSpheres;
  scene.replace(scene.find("<sensor"), 0, "<default name=\"w\" value=\"32\"/>\n  ");
  scene.replace(scene.find("value=\"32\"/><integer name=\"height\""), 10, "value=\"$w\"/>");
  const std::string xml = write_temp_file("defaults.xml", scene);
  std::string err, out;
  ASSERT_EQ(run_pathcl("info " + xml, &err, &out), 0) << err;
  EXPECT_NE(out.find("camera: 32x16"), std::string::npos) << out;
  ASSERT_EQ(run_pathcl("info " + xml + " -D w=8", &err, &out), 0) << err;
  EXPECT_NE(out.find("camera: 8x16"), std::string::npos) << out;
  EXPECT_EQ(run_pathcl("info " + xml + " -D w", &err), 2);
  EXPECT_NE(err.find("-D w: expected NAME=VALUE"), std::string::npos) << err;
  EXPECT_EQ(run_pathcl("info " + write_temp_file("d.pbrt", kPbrtSpheres) + " -D w=8", &err), 2);
  EXPECT_NE(err.find("sets a Mitsuba <default>, and this is a pbrt scene"), std::string::npos) << err;
  const std::string undefined = write_temp_file("undefined.xml", std::string(kMitsubaSpheres).replace(
                                                                      std::string(kMitsubaSpheres).find("value=\"4\""), 9, "value=\"$spp\""));
  EXPECT_EQ(run_pathcl("info " + undefined, &err), 2);
  EXPECT_NE(err.find("undefined.xml:5: undefined parameter $spp"), std::string::npos) << err;
  EXPECT_EQ(run_pathcl("info " + undefined + " -D spp=2", &err), 0) << err;
}
