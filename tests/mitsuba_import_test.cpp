// Mitsuba 0.6 and 3 XML scenes (scene/mitsuba_import.cpp): small files this test writes give the pathcl
// JSON that docs/scene-format.md ("Mitsuba XML scenes") describes, plugin by plugin (numbers compared with Mitsuba 3.9's where
// it computes them: fields of view, the plastic's diffuse lobe, shape layouts); 0.6 names are upgraded;
// defaults, includes, references and instances resolve; bad input names its file and line; checkerboards
// give Mitsuba's tiles on the same points; cylinders are tessellated to their area; the Cornell box of
// tests/scenes/mitsuba imports and loads.
#include <cmath>
#include <filesystem>
#include <random>
#include <sstream>

#include <gtest/gtest.h>
#include <glm/glm.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <nlohmann/json.hpp>

#include "kernels/shared/types.h"
#include "scene/scene_description.h"
#include "scene/scene_error.h"
#include "scene/scene_import.h"
#include "scene/spectrum.h"
#include "test_support.h"

using nlohmann::json;

namespace {

std::string path_of(const std::string& name) { return temp_dir() + "/mitsuba/" + name; }

// Writes the XML to NAME in this test's directory and imports it.
ImportedScene import_file(const std::string& name, const std::string& xml) {
  return import_mitsuba_xml(write_temp_file("mitsuba/" + name, xml), xml);
}

// The message of the SceneError importing the XML throws ("" if it imports).
std::string import_error(const std::string& name, const std::string& xml) {
  try {
    import_file(name, xml);
  } catch (const SceneError& e) {
    return e.what();
  }
  return "";
}

// A Mitsuba 3 scene with a default camera; `body` starts on line 3.
std::string scene3(const std::string& body) {
  return "<scene version=\"3.0.0\">\n<sensor type=\"perspective\"/>\n" + body + "\n</scene>\n";
}

// The message starts with the place ("FILE:LINE: ") and says `what`.
testing::AssertionResult error_is(const std::string& message, const std::string& place, const std::string& what) {
  if (message.rfind(place, 0) == 0 && message.find(what) != std::string::npos) return testing::AssertionSuccess();
  return testing::AssertionFailure() << "the message \"" << message << "\" does not start with \"" << place
                                     << "\" and say \"" << what << "\"";
}

bool has_warning(const ImportedScene& s, const std::string& part) {
  for (const std::string& w : s.warnings)
    if (w.find(part) != std::string::npos) return true;
  return false;
}

std::string warnings_of(const ImportedScene& s) {
  std::string all;
  for (const std::string& w : s.warnings) all += w + "\n";
  return all;
}

glm::dvec3 vec(const json& j) { return {j.at(0).get<double>(), j.at(1).get<double>(), j.at(2).get<double>()}; }

glm::dmat4 matrix(const json& transform) {
  glm::dmat4 m(1.0);
  const json& rows = transform.at("matrix");
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) m[c][r] = rows.at(r).at(c).get<double>();
  return m;
}

void expect_vec(const json& j, glm::dvec3 expected, double tolerance = 1e-9) {
  glm::dvec3 v = vec(j);
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(v[i], expected[i], tolerance) << "component " << i << " of " << j.dump();
}

void expect_matrix(const json& transform, const glm::dmat4& expected, double tolerance = 1e-9) {
  glm::dmat4 m = matrix(transform);
  for (int c = 0; c < 4; ++c)
    for (int r = 0; r < 4; ++r) EXPECT_NEAR(m[c][r], expected[c][r], tolerance) << "row " << r << ", column " << c;
}

std::string origin_of(const ImportedScene& s, const std::string& json_path) {
  for (const auto& [path, place] : s.origins)
    if (path == json_path) return place;
  return "";
}

double degrees(double radians) { return radians * 180 / M_PI; }
double radians(double degrees) { return degrees * M_PI / 180; }

// A camera with this film size and these sensor parameters.
std::string camera_scene(const std::string& sensor, int width = 200, int height = 100) {
  return "<scene version=\"3.0.0\">\n<sensor type=\"perspective\">\n" + sensor +
         "\n<film type=\"hdrfilm\"><integer name=\"width\" value=\"" + std::to_string(width) +
         "\"/><integer name=\"height\" value=\"" + std::to_string(height) + "\"/></film>\n</sensor>\n</scene>\n";
}

double fov_y(const std::string& sensor) {
  return import_file("fov.xml", camera_scene(sensor)).scene.at("camera").at("fov_y_degrees").get<double>();
}

}  // namespace

// ---------------------------------------------------------------------------------------------------
// Sensor, film, sampler, integrator

TEST(MitsubaImport, LookAtCameraGivesPositionLookAtUpAndVerticalFov) {
  ImportedScene s = import_file("camera.xml", camera_scene(R"(<float name="fov" value="60"/>
<transform name="to_world"><lookat origin="1, 2, 3" target="1, 2, -7" up="0, 1, 0"/></transform>)"));
  const json& c = s.scene.at("camera");
  EXPECT_EQ(c.at("type"), "perspective");
  expect_vec(c.at("position"), {1, 2, 3});
  expect_vec(c.at("look_at"), {1, 2, 2});
  expect_vec(c.at("up"), {0, 1, 0});
  EXPECT_EQ(c.at("width"), 200);
  EXPECT_EQ(c.at("height"), 100);
  // fov_axis x (the default) with a 2:1 film: tan(fov_y / 2) = tan(30 degrees) / 2.
  EXPECT_NEAR(c.at("fov_y_degrees").get<double>(), degrees(2 * std::atan(std::tan(radians(30)) / 2)), 1e-9);
  EXPECT_FALSE(c.contains("handedness"));
  // Mitsuba's default film filter and sampler.
  EXPECT_EQ(c.at("filter"), (json{{"type", "gaussian"}, {"sigma", 0.5}, {"radius", 2.0}}));
  EXPECT_EQ(s.scene.at("render"),
            (json{{"spp", 4}, {"seed", 0}, {"sampler", "independent"}, {"integrator", "path"}, {"max_depth", 1024}}));
  EXPECT_TRUE(has_warning(s, "no <integrator>")) << warnings_of(s);
  EXPECT_EQ(origin_of(s, "camera"), path_of("camera.xml") + ":2: sensor \"perspective\"");
  EXPECT_EQ(origin_of(s, "camera.width"), path_of("camera.xml") + ":5: film \"hdrfilm\"");
}

// Mitsuba 3.9's own x_fov for a 200 x 100 film (mi.traverse(sensor)['x_fov']), as pathcl's fov_y.
TEST(MitsubaImport, FovAxesAndFocalLengthsGiveMitsubasFieldOfView) {
  // Mitsuba's x_fov is a float: within 1e-5 degrees.
  EXPECT_NEAR(fov_y(""), 21.90213746, 1e-5);  // 50mm, the default
  EXPECT_NEAR(fov_y(R"(<string name="focal_length" value="35mm"/>)"), 30.9037556, 1e-5);
  EXPECT_NEAR(fov_y(R"(<float name="fov" value="30"/><string name="fov_axis" value="y"/>)"), 30, 1e-9);
  EXPECT_NEAR(fov_y(R"(<float name="fov" value="30"/><string name="fov_axis" value="diagonal"/>)"), 13.6664009, 1e-5);
  EXPECT_NEAR(fov_y(R"(<float name="fov" value="30"/><string name="fov_axis" value="smaller"/>)"), 30, 1e-9);
  EXPECT_NEAR(fov_y(R"(<float name="fov" value="30"/><string name="fov_axis" value="larger"/>)"),
              degrees(2 * std::atan(std::tan(radians(15)) / 2)), 1e-9);
  EXPECT_TRUE(error_is(
      import_error("fov.xml", camera_scene(R"(<float name="fov" value="30"/><string name="fov_axis" value="z"/>)")),
      path_of("fov.xml") + ":3: ", "fov_axis \"z\" (expected x, y, diagonal, smaller or larger)"));
}

TEST(MitsubaImport, MirroredCameraIsLeftHanded) {
  ImportedScene s = import_file("mirror.xml", camera_scene(R"(<transform name="to_world"><scale x="-1"/>
<lookat origin="0, 0, 5" target="0, 0, 0" up="0, 1, 0"/></transform>)"));
  const json& c = s.scene.at("camera");
  EXPECT_EQ(c.at("handedness"), "left");
  expect_vec(c.at("position"), {0, 0, 5});
  expect_vec(c.at("look_at"), {0, 0, 4});
  expect_vec(c.at("up"), {0, 1, 0});
  EXPECT_TRUE(
      error_is(import_error("scaled.xml", camera_scene(R"(<transform name="to_world"><scale value="2"/></transform>)")),
               path_of("scaled.xml") + ":3: ", "to_world scales or shears"));
}

TEST(MitsubaImport, ThinLensTakesApertureAndFocusDistance) {
  ImportedScene s = import_file("lens.xml", R"(<scene version="3.0.0">
<sensor type="thinlens"><float name="aperture_radius" value="0.1"/><float name="focus_distance" value="4"/></sensor>
</scene>)");
  const json& c = s.scene.at("camera");
  EXPECT_EQ(c.at("type"), "thin_lens");
  EXPECT_EQ(c.at("aperture_radius"), 0.1);
  EXPECT_EQ(c.at("focus_distance"), 4.0);
  ImportedScene clipped = import_file("clip.xml", camera_scene(R"(<float name="far_clip" value="50"/>)"));
  EXPECT_TRUE(has_warning(clipped, "near_clip and far_clip are not supported")) << warnings_of(clipped);
}

TEST(MitsubaImport, FiltersAndSamplers) {
  auto filter_of = [](const std::string& rfilter) {
    ImportedScene s =
        import_file("filter.xml", "<scene version=\"3.0.0\"><sensor type=\"perspective\"><film type=\"hdrfilm\">" +
                                      rfilter + "</film></sensor></scene>");
    return std::make_pair(s.scene.at("camera").at("filter"), s.warnings);
  };
  EXPECT_EQ(filter_of(R"(<rfilter type="box"/>)").first, (json{{"type", "box"}}));
  EXPECT_EQ(filter_of(R"(<rfilter type="tent"><float name="radius" value="2"/></rfilter>)").first,
            (json{{"type", "tent"}, {"radius", 2.0}}));
  EXPECT_EQ(filter_of(R"(<rfilter type="gaussian"><float name="stddev" value="0.25"/></rfilter>)").first,
            (json{{"type", "gaussian"}, {"sigma", 0.25}, {"radius", 1.0}}));
  auto [mitchell, warnings] = filter_of(R"(<rfilter type="mitchell"/>)");
  EXPECT_EQ(mitchell, (json{{"type", "box"}}));
  ASSERT_EQ(warnings.size(), 2u);  // the box, and the missing integrator
  EXPECT_NE(warnings[0].find("rfilter \"mitchell\" becomes a box filter"), std::string::npos) << warnings[0];

  auto render_of = [](const std::string& sampler) {
    return import_file("sampler.xml",
                       "<scene version=\"3.0.0\"><sensor type=\"perspective\">" + sampler + "</sensor></scene>");
  };
  ImportedScene stratified = render_of(
      R"(<sampler type="stratified"><integer name="sample_count" value="10"/><integer name="seed" value="7"/></sampler>)");
  EXPECT_EQ(stratified.scene.at("render").at("spp"), 16);  // rounded up to a square, as Mitsuba does
  EXPECT_EQ(stratified.scene.at("render").at("seed"), 7);
  EXPECT_EQ(stratified.scene.at("render").at("sampler"), "stratified");
  EXPECT_TRUE(has_warning(stratified, "sample_count 10 becomes 16")) << warnings_of(stratified);
  ImportedScene multijitter =
      render_of(R"(<sampler type="multijitter"><integer name="sample_count" value="64"/></sampler>)");
  EXPECT_EQ(multijitter.scene.at("render").at("sampler"), "stratified");
  EXPECT_EQ(multijitter.scene.at("render").at("spp"), 64);
  EXPECT_TRUE(has_warning(multijitter, "the same expected image")) << warnings_of(multijitter);
  EXPECT_EQ(render_of(R"(<sampler type="ldsampler"><integer name="sample_count" value="20"/></sampler>)")
                .scene.at("render")
                .at("spp"),
            64);
}

TEST(MitsubaImport, FilmsRefuseCropsAndTellToneMapping) {
  EXPECT_TRUE(error_is(import_error("crop.xml", R"(<scene version="3.0.0">
<sensor type="perspective">
<film type="hdrfilm"><integer name="crop_width" value="10"/></film>
</sensor>
</scene>)"),
                       path_of("crop.xml") + ":3: ", "crop windows are not supported"));
  ImportedScene ldr = import_file(
      "ldr.xml",
      R"(<scene version="3.0.0"><sensor type="perspective"><film type="ldrfilm"><float name="exposure" value="1"/></film></sensor></scene>)");
  EXPECT_TRUE(has_warning(ldr, "tone mapping is not applied")) << warnings_of(ldr);
}

TEST(MitsubaImport, IntegratorDepthsCountScatteringEvents) {
  auto render_of = [](const std::string& integrator) { return import_file("integrator.xml", scene3(integrator)); };
  auto depth = [&](int mitsuba_depth) {
    return render_of("<integrator type=\"path\"><integer name=\"max_depth\" value=\"" + std::to_string(mitsuba_depth) +
                     "\"/></integrator>")
        .scene.at("render")
        .at("max_depth")
        .get<int>();
  };
  EXPECT_EQ(depth(1), 0);  // emitters seen directly
  EXPECT_EQ(depth(2), 1);  // direct lighting
  EXPECT_EQ(depth(8), 7);
  ImportedScene unbounded = render_of(R"(<integrator type="path"><integer name="max_depth" value="-1"/></integrator>)");
  EXPECT_EQ(unbounded.scene.at("render").at("max_depth"), 1024);
  EXPECT_TRUE(has_warning(unbounded, "max_depth -1 (unbounded) becomes pathcl's largest")) << warnings_of(unbounded);
  EXPECT_TRUE(
      error_is(import_error("depth0.xml",
                            scene3(R"(<integrator type="path"><integer name="max_depth" value="0"/></integrator>)")),
               path_of("depth0.xml") + ":3: ", "max_depth 0 renders nothing"));

  ImportedScene direct =
      render_of(R"(<integrator type="direct"><integer name="emitter_samples" value="4"/></integrator>)");
  EXPECT_EQ(direct.scene.at("render").at("integrator"), "path");
  EXPECT_EQ(direct.scene.at("render").at("max_depth"), 1);
  EXPECT_TRUE(has_warning(direct, "4 emitter and 1 bsdf samples")) << warnings_of(direct);
  EXPECT_EQ(
      render_of(R"(<integrator type="volpath"><integer name="max_depth" value="5"/></integrator>)").scene.at("render"),
      (json{{"spp", 4}, {"seed", 0}, {"sampler", "independent"}, {"integrator", "path"}, {"max_depth", 4}}));
  EXPECT_EQ(render_of(R"(<integrator type="bdpt"><integer name="max_depth" value="6"/></integrator>)")
                .scene.at("render")
                .at("integrator"),
            "bdpt");
  ImportedScene ptracer = render_of(R"(<integrator type="ptracer"><integer name="max_depth" value="3"/></integrator>)");
  EXPECT_EQ(ptracer.scene.at("render").at("integrator"), "light");
  EXPECT_EQ(ptracer.scene.at("render").at("max_depth"), 2);
  ImportedScene aov = render_of(R"(<integrator type="aov"><string name="aovs" value="dd.y:depth"/>
<integrator type="path"><integer name="max_depth" value="4"/></integrator></integrator>)");
  EXPECT_EQ(aov.scene.at("render").at("max_depth"), 3);
  EXPECT_TRUE(has_warning(aov, "integrator \"aov\" is not supported: its nested integrator \"path\" renders the image"))
      << warnings_of(aov);
  EXPECT_TRUE(error_is(import_error("pm.xml", scene3(R"(<integrator type="photonmapper"/>)")),
                       path_of("pm.xml") + ":3: ", "integrator \"photonmapper\" is not supported (supported: path"));
}

// ---------------------------------------------------------------------------------------------------
// Transforms and shapes

TEST(MitsubaImport, TransformsComposeInDocumentOrder) {
  ImportedScene s = import_file("transform.xml", scene3(R"(<shape type="rectangle"><transform name="to_world">
  <scale value="2"/>
  <rotate y="1" angle="90"/>
  <translate value="1 2 3"/>
</transform></shape>
<shape type="rectangle"><transform name="to_world"><matrix value="1 0 0 4  0 0 -1 5  0 1 0 6  0 0 0 1"/></transform></shape>
<shape type="rectangle"><transform name="to_world"><translate x="1"/><lookat origin="0, 0, 0" target="0, 0, 1" up="0, 1, 0"/></transform></shape>)"));
  const json& shapes = s.scene.at("shapes");
  ASSERT_EQ(shapes.size(), 3u);
  // translate * rotate * scale: (1, 0, 0) -> (2, 0, 0) -> (0, 0, -2) -> (1, 2, 1).
  glm::dmat4 m = matrix(shapes[0].at("transform"));
  glm::dvec4 p = m * glm::dvec4(1, 0, 0, 1);
  EXPECT_NEAR(p.x, 1, 1e-12);
  EXPECT_NEAR(p.y, 2, 1e-12);
  EXPECT_NEAR(p.z, 1, 1e-12);
  glm::dmat4 expected = glm::translate(glm::dmat4(1), {1, 2, 3}) * glm::rotate(glm::dmat4(1), radians(90), {0, 1, 0}) *
                        glm::scale(glm::dmat4(1), glm::dvec3(2));
  expect_matrix(shapes[0].at("transform"), expected, 1e-12);
  // <matrix> is written row by row.
  glm::dvec4 q = matrix(shapes[1].at("transform")) * glm::dvec4(0, 1, 0, 1);
  EXPECT_NEAR(q.x, 4, 1e-12);
  EXPECT_NEAR(q.y, 5, 1e-12);
  EXPECT_NEAR(q.z, 7, 1e-12);
  // Mitsuba's lookat: columns left = cross(up, dir), up, dir, origin; here after a translation by x.
  glm::dmat4 lookat_after = matrix(shapes[2].at("transform"));
  glm::dvec4 r = lookat_after * glm::dvec4(0, 0, 0, 1);
  EXPECT_NEAR(r.x, 1, 1e-12);  // left = cross((0, 1, 0), (0, 0, 1)) = (1, 0, 0)
}

TEST(MitsubaImport, RectangleCubeAndDiskBecomeTrianglesFacingMitsubasNormals) {
  ImportedScene s = import_file("shapes.xml", scene3(R"(<shape type="rectangle"/>
<shape type="rectangle"><boolean name="flip_normals" value="true"/></shape>
<shape type="cube"/>
<shape type="disk"/>)"));
  const json& shapes = s.scene.at("shapes");
  ASSERT_EQ(shapes.size(), 4u);
  const json& rect = shapes[0];
  EXPECT_EQ(rect.at("type"), "triangles");
  EXPECT_EQ(rect.at("positions"), (json{{-1.0, -1.0, 0.0}, {1.0, -1.0, 0.0}, {-1.0, 1.0, 0.0}, {1.0, 1.0, 0.0}}));
  EXPECT_EQ(rect.at("indices"), (json{{1, 2, 0}, {1, 3, 2}}));
  // Mitsuba's uv ((x + 1) / 2, (y + 1) / 2) with v = 0 at an image's top row; pathcl's v = 0 is its bottom.
  EXPECT_EQ(rect.at("uvs"), (json{{0.0, 1.0}, {1.0, 1.0}, {0.0, 0.0}, {1.0, 0.0}}));
  EXPECT_EQ(shapes[1].at("indices"), (json{{1, 0, 2}, {1, 2, 3}}));

  // Every face counter-clockwise seen from outside the cube, and from +z for the rectangle and disk.
  auto normals = [](const json& shape) {
    std::vector<std::pair<glm::dvec3, glm::dvec3>> out;  // (normal, centroid)
    for (const json& f : shape.at("indices")) {
      glm::dvec3 a = vec(shape.at("positions")[f[0].get<int>()]), b = vec(shape.at("positions")[f[1].get<int>()]),
                 c = vec(shape.at("positions")[f[2].get<int>()]);
      out.push_back({glm::cross(b - a, c - a), (a + b + c) / 3.0});
    }
    return out;
  };
  const json& cube = shapes[2];
  EXPECT_EQ(cube.at("positions").size(), 24u);
  EXPECT_EQ(cube.at("indices").size(), 12u);
  for (auto [n, centroid] : normals(cube)) EXPECT_GT(glm::dot(n, centroid), 0);
  for (auto [n, centroid] : normals(rect)) EXPECT_GT(n.z, 0);
  // The disk's fan has the unit disk's area, each triangle facing +z.
  const json& disk = shapes[3];
  double area = 0;
  for (auto [n, centroid] : normals(disk)) {
    EXPECT_GT(n.z, 0);
    area += glm::length(n) / 2;
  }
  EXPECT_NEAR(area, M_PI, 1e-9);
  EXPECT_TRUE(has_warning(s, "tessellated into 256 triangles")) << warnings_of(s);
}

TEST(MitsubaImport, MeshFilesAndSpheres) {
  ImportedScene s = import_file("meshes.xml", scene3(R"(<bsdf type="twosided" id="grey"><bsdf type="diffuse"/></bsdf>
<shape type="obj"><string name="filename" value="meshes/bunny.obj"/><ref id="grey"/></shape>
<shape type="ply"><string name="filename" value="scan.ply"/><boolean name="face_normals" value="true"/><ref id="grey"/>
  <transform name="to_world"><translate x="2"/></transform></shape>
<shape type="sphere"><point name="center" x="1" y="2" z="3"/><float name="radius" value="0.5"/>
  <boolean name="flip_normals" value="true"/><ref id="grey"/></shape>)"));
  const json& shapes = s.scene.at("shapes");
  ASSERT_EQ(shapes.size(), 3u);
  EXPECT_EQ(shapes[0], (json{{"type", "mesh"},
                             {"file", "meshes/bunny.obj"},
                             {"vertex_colors", false},
                             {"smooth", true},
                             {"smooth_angle_degrees", 180},
                             {"material", "grey"}}));
  EXPECT_EQ(shapes[1].at("file"), "scan.ply");
  EXPECT_FALSE(shapes[1].contains("smooth"));
  expect_matrix(shapes[1].at("transform"), glm::translate(glm::dmat4(1), {2, 0, 0}));
  EXPECT_EQ(shapes[2], (json{{"type", "sphere"},
                             {"center", {1.0, 2.0, 3.0}},
                             {"radius", 0.5},
                             {"flip_normals", true},
                             {"material", "grey"}}));
  EXPECT_EQ(s.warnings.size(), 1u) << warnings_of(s);  // the missing integrator only
  EXPECT_EQ(origin_of(s, "shapes[1]"), path_of("meshes.xml") + ":5: shape \"ply\"");

  // A .serialized file: a mesh with the shape's shape_index (scene/serialized_load.h reads it).
  const ImportedScene ser = import_file(
      "serialized.xml", scene3(R"(<shape type="serialized"><string name="filename" value="a.serialized"/>
        <integer name="shape_index" value="2"/><boolean name="face_normals" value="true"/></shape>)"));
  EXPECT_EQ(ser.scene["shapes"][0]["type"], "mesh");
  EXPECT_EQ(ser.scene["shapes"][0]["file"], "a.serialized");
  EXPECT_EQ(ser.scene["shapes"][0]["shape_index"], 2);
  EXPECT_FALSE(ser.scene["shapes"][0].contains("smooth"));
  EXPECT_TRUE(error_is(
      import_error("serialized.xml",
                   scene3(R"(<shape type="serialized"><string name="filename" value="a.serialized"/>
                     <integer name="shape_index" value="-1"/></shape>)")),
      path_of("serialized.xml") + ":4: ", "shape_index >= 0"));
  EXPECT_TRUE(
      error_is(import_error("flipped.xml", scene3(R"(<shape type="obj"><string name="filename" value="lamp.obj"/>
<boolean name="flip_normals" value="true"/><emitter type="area"/></shape>)")),
               path_of("flipped.xml") + ":4: ", "flip_normals on an emitting mesh file is not supported"));
  ImportedScene ply = import_file("plytex.xml", scene3(R"(<shape type="ply"><string name="filename" value="scan.ply"/>
<bsdf type="twosided"><bsdf type="diffuse"><texture type="bitmap" name="reflectance"><string name="filename" value="wood.png"/></texture></bsdf></bsdf></shape>)"));
  EXPECT_TRUE(has_warning(ply, "the texture appears flipped vertically")) << warnings_of(ply);
}

TEST(MitsubaImport, ShapegroupInstancesComposeTheirTransforms) {
  ImportedScene s = import_file("instances.xml", scene3(R"(<shape type="shapegroup" id="pair">
  <shape type="sphere"><float name="radius" value="0.5"/></shape>
  <shape type="rectangle"><transform name="to_world"><translate x="1"/></transform></shape>
</shape>
<shape type="instance"><ref id="pair"/><transform name="to_world"><translate z="5"/></transform></shape>
<shape type="instance"><ref id="pair"/><transform name="to_world"><scale value="2"/></transform></shape>)"));
  const json& shapes = s.scene.at("shapes");
  ASSERT_EQ(shapes.size(), 4u);
  EXPECT_EQ(shapes[0].at("type"), "sphere");
  expect_matrix(shapes[0].at("transform"), glm::translate(glm::dmat4(1), {0, 0, 5}));
  expect_matrix(shapes[1].at("transform"), glm::translate(glm::dmat4(1), {1, 0, 5}));
  expect_matrix(shapes[2].at("transform"), glm::scale(glm::dmat4(1), glm::dvec3(2)));
  expect_matrix(shapes[3].at("transform"),
                glm::scale(glm::dmat4(1), glm::dvec3(2)) * glm::translate(glm::dmat4(1), {1, 0, 0}));
  // Shapes without a bsdf take Mitsuba's default, a one-sided diffuse 0.5.
  EXPECT_EQ(shapes[0].at("material"), "default");
  EXPECT_EQ(s.scene.at("materials").at("default"), (json{{"type", "diffuse"}, {"reflectance", {0.5, 0.5, 0.5}}}));
  EXPECT_TRUE(has_warning(s, "Mitsuba's default, a one-sided diffuse")) << warnings_of(s);
}

// ---------------------------------------------------------------------------------------------------
// Emitters

TEST(MitsubaImport, AreaEmittersFollowMitsubasSpectrumConventions) {
  ImportedScene s = import_file(
      "area.xml",
      scene3(R"(<shape type="rectangle"><emitter type="area"><rgb name="radiance" value="1 2 3"/></emitter></shape>
<shape type="rectangle"><emitter type="area"><spectrum name="radiance" value="5"/></emitter></shape>
<shape type="rectangle"><emitter type="area"><spectrum name="radiance" value="400:0, 500:8, 600:15.6, 700:18.4"/></emitter></shape>
<shape type="rectangle"><emitter type="area"><float name="radiance" value="2"/></emitter></shape>)"));
  const json& shapes = s.scene.at("shapes");
  ASSERT_EQ(shapes.size(), 4u);
  expect_vec(shapes[0].at("emission"), {1, 2, 3});
  // A uniform spectrum on an emitter is v xyz_to_srgb(1, 1, 1), slightly purple, as in Mitsuba's RGB variants.
  expect_vec(shapes[1].at("emission"), uniform_emission_to_srgb(5));
  expect_vec(shapes[2].at("emission"), emission_spectrum_to_srgb({400, 500, 600, 700}, {0, 8, 15.6, 18.4}));
  expect_vec(shapes[3].at("emission"), {2, 2, 2});
  // Emitters without a bsdf are black (Mitsuba's default for them); no one-sided warning.
  EXPECT_EQ(shapes[0].at("material"), "default-emitter");
  EXPECT_EQ(s.scene.at("materials").at("default-emitter"),
            (json{{"type", "diffuse"}, {"reflectance", {0.0, 0.0, 0.0}}}));
  EXPECT_EQ(origin_of(s, "shapes[2].emission"), path_of("area.xml") + ":5: emitter \"area\"");
  EXPECT_FALSE(s.scene.contains("lights"));

  // An area emitter at the top level, with an id, is the shapes' that refer to it, before or after it in
  // the file (mitsuba-data's cbox-rgb.xml); one that no shape takes is an error.
  ImportedScene by_id = import_file("area-id.xml", scene3(R"(<shape type="rectangle"><ref id="lamp"/></shape>
<emitter type="area" id="lamp"><rgb name="radiance" value="4 5 6"/></emitter>)"));
  ASSERT_EQ(by_id.scene.at("shapes").size(), 1u);
  expect_vec(by_id.scene.at("shapes")[0].at("emission"), {4, 5, 6});
  EXPECT_TRUE(error_is(import_error("area-alone.xml", scene3(R"(<shape type="rectangle"/>
<emitter type="area" id="lamp"><rgb name="radiance" value="4 5 6"/></emitter>)")),
                       path_of("area-alone.xml") + ":4: ", "is on no shape"));
}

TEST(MitsubaImport, PointSpotAndDirectionalLights) {
  ImportedScene s = import_file(
      "lights.xml",
      scene3(
          R"(<emitter type="point"><point name="position" value="1, 2, 3"/><rgb name="intensity" value="10"/></emitter>
<emitter type="point"><transform name="to_world"><translate x="4"/></transform></emitter>
<emitter type="spot"><transform name="to_world"><lookat origin="0, 5, 0" target="0, 0, 0" up="0, 0, 1"/></transform>
  <float name="cutoff_angle" value="30"/><rgb name="intensity" value="7"/></emitter>
<emitter type="directional"><vector name="direction" value="0, -1, 0"/><rgb name="irradiance" value="3"/></emitter>
<emitter type="directional"><transform name="to_world"><rotate x="1" angle="90"/></transform></emitter>)"));
  const json& lights = s.scene.at("lights");
  ASSERT_EQ(lights.size(), 5u);
  EXPECT_EQ(lights[0], (json{{"type", "point"}, {"position", {1.0, 2.0, 3.0}}, {"intensity", {10.0, 10.0, 10.0}}}));
  EXPECT_EQ(lights[1], (json{{"type", "point"}, {"position", {4.0, 0.0, 0.0}}, {"intensity", {1.0, 1.0, 1.0}}}));
  expect_vec(lights[2].at("position"), {0, 5, 0});
  expect_vec(lights[2].at("direction"), {0, -1, 0});
  EXPECT_EQ(lights[2].at("outer_angle_degrees"), 30.0);
  EXPECT_EQ(lights[2].at("inner_angle_degrees"), 22.5);  // beam_width: 3/4 of the cutoff by default
  EXPECT_TRUE(has_warning(s, "falls linearly in the angle, pathcl's as a smoothstep")) << warnings_of(s);
  EXPECT_EQ(lights[3],
            (json{{"type", "directional"}, {"direction", {0.0, -1.0, 0.0}}, {"irradiance", {3.0, 3.0, 3.0}}}));
  expect_vec(lights[4].at("direction"), {0, -1, 0});  // +z rotated by 90 degrees about x
  EXPECT_EQ(origin_of(s, "lights[2]"), path_of("lights.xml") + ":5: emitter \"spot\"");
}

// pathcl's lat-long lookup at T^-1 w must be Mitsuba's at to_world^-1 w, for every direction w.
TEST(MitsubaImport, EnvironmentMapTransformMatchesMitsubasLookup) {
  ImportedScene s = import_file(
      "envmap.xml",
      scene3(R"(<emitter type="envmap"><string name="filename" value="sky.exr"/><float name="scale" value="2"/>
<transform name="to_world"><rotate y="1" angle="70"/><rotate x="1" angle="20"/></transform></emitter>)"));
  const json& env = s.scene.at("lights").at(0);
  EXPECT_EQ(env.at("type"), "environment");
  EXPECT_EQ(env.at("file"), "sky.exr");
  EXPECT_EQ(env.at("scale"), 2.0);
  const glm::dmat3 t(matrix(env.at("transform")));
  const glm::dmat3 to_world(glm::rotate(glm::dmat4(1), radians(20), {1, 0, 0}) *
                            glm::rotate(glm::dmat4(1), radians(70), {0, 1, 0}));
  auto wrap = [](double u) { return u - std::floor(u); };
  for (int i = 0; i < 200; ++i) {
    glm::dvec3 w = glm::normalize(glm::dvec3(std::sin(i * 1.3), std::cos(i * 0.7) * 0.9, std::sin(i * 2.9 + 1)));
    glm::dvec3 d = glm::inverse(to_world) * w, e = glm::inverse(t) * w;
    double mitsuba_u = wrap(std::atan2(d.x, -d.z) / (2 * M_PI)), mitsuba_v = std::acos(d.y) / M_PI;
    double pathcl_u = wrap(std::atan2(e.z, e.x) / (2 * M_PI)), pathcl_v = std::acos(std::clamp(e.y, -1.0, 1.0)) / M_PI;
    double du = std::abs(mitsuba_u - pathcl_u);
    EXPECT_LT(std::min(du, 1 - du), 1e-9) << i;
    EXPECT_NEAR(mitsuba_v, pathcl_v, 1e-9) << i;
  }
  EXPECT_TRUE(
      error_is(import_error("envscale.xml", scene3(R"(<emitter type="envmap"><string name="filename" value="sky.exr"/>
<transform name="to_world"><scale value="2"/></transform></emitter>)")),
               path_of("envscale.xml") + ":4: ", "to_world must be a rotation"));
  EXPECT_TRUE(error_is(import_error("twoenv.xml", scene3(R"(<emitter type="constant"/>
<emitter type="constant"/>)")),
                       path_of("twoenv.xml") + ":4: ", "a second environment emitter"));
  ImportedScene constant = import_file(
      "constant.xml", scene3(R"(<emitter type="constant"><rgb name="radiance" value="0.5 1 2"/></emitter>)"));
  EXPECT_EQ(constant.scene.at("lights").at(0), (json{{"type", "environment"}, {"radiance", {0.5, 1.0, 2.0}}}));
}

// ---------------------------------------------------------------------------------------------------
// BSDFs

TEST(MitsubaImport, DiffuseTwosidedAndTextures) {
  ImportedScene s = import_file("diffuse.xml", scene3(R"(<bsdf type="twosided" id="spectral"><bsdf type="diffuse">
  <spectrum name="reflectance" value="400:0.2, 500:0.4, 600:0.6, 700:0.5"/></bsdf></bsdf>
<bsdf type="twosided" id="wood"><bsdf type="diffuse"><texture type="bitmap" name="reflectance">
  <string name="filename" value="textures/wood.png"/><string name="wrap_mode" value="mirror"/></texture></bsdf></bsdf>
<bsdf type="diffuse" id="onesided"><rgb name="reflectance" value="0.2 0.4 1.5"/></bsdf>
<bsdf type="twosided" id="uniform"><bsdf type="diffuse"><spectrum name="reflectance" value="0.3"/></bsdf></bsdf>)"));
  const json& m = s.scene.at("materials");
  EXPECT_EQ(m.at("spectral").at("type"), "diffuse");
  expect_vec(m.at("spectral").at("reflectance"),
             reflectance_spectrum_to_srgb({400, 500, 600, 700}, {0.2, 0.4, 0.6, 0.5}));
  EXPECT_EQ(m.at("wood"),
            (json{{"type", "diffuse"}, {"reflectance", {{"texture", "textures/wood.png"}, {"wrap", "mirror"}}}}));
  expect_vec(m.at("onesided").at("reflectance"), {0.2, 0.4, 1.0});  // clamped, with a warning
  expect_vec(m.at("uniform").at("reflectance"), {0.3, 0.3, 0.3});   // a uniform reflectance is grey, not purple
  EXPECT_TRUE(has_warning(s, "reflectance (0.2, 0.4, 1.5) is clamped into [0, 1]")) << warnings_of(s);
  EXPECT_TRUE(has_warning(s, path_of("diffuse.xml") + ":7: bsdf \"diffuse\" (id \"onesided\") is one-sided in Mitsuba"))
      << warnings_of(s);
  EXPECT_EQ(s.warnings.size(), 3u) << warnings_of(s);  // clamped, one-sided, no integrator
  EXPECT_EQ(origin_of(s, "materials.wood"), path_of("diffuse.xml") + ":5: bsdf \"twosided\" (id \"wood\")");
}

TEST(MitsubaImport, DielectricTakesTheRelativeIndexOfRefraction) {
  ImportedScene s = import_file(
      "glass.xml",
      scene3(
          R"(<bsdf type="dielectric" id="water"><string name="int_ior" value="water"/><string name="ext_ior" value="air"/>
  <rgb name="specular_transmittance" value="0.9 1 0.9"/></bsdf>
<bsdf type="dielectric" id="numbers"><float name="int_ior" value="1.8"/><float name="ext_ior" value="1.2"/></bsdf>
<bsdf type="dielectric" id="default"/>
<bsdf type="roughdielectric" id="rough"><float name="alpha" value="0.2"/></bsdf>)"));
  const json& m = s.scene.at("materials");
  double water = 0, air = 0, bk7 = 0;
  ASSERT_TRUE(named_ior("water", &water) && named_ior("air", &air) && named_ior("bk7", &bk7));
  EXPECT_NEAR(m.at("water").at("ior").get<double>(), water / air, 1e-12);
  expect_vec(m.at("water").at("transmittance"), {0.9, 1, 0.9});
  EXPECT_NEAR(m.at("numbers").at("ior").get<double>(), 1.5, 1e-12);
  EXPECT_NEAR(m.at("default").at("ior").get<double>(), bk7 / air, 1e-12);  // Mitsuba: bk7 inside, air outside
  EXPECT_EQ(m.at("rough").at("type"), "dielectric");
  EXPECT_TRUE(has_warning(s, "rendered as smooth glass")) << warnings_of(s);
  EXPECT_FALSE(has_warning(s, "one-sided")) << warnings_of(s);
  ImportedScene thin = import_file(
      "thin.xml", scene3(R"(<bsdf type="thindielectric" id="pane"><float name="int_ior" value="1.5"/></bsdf>)"));
  EXPECT_EQ(thin.scene.at("materials").at("pane").at("type"), "thin_dielectric");
  EXPECT_NEAR(thin.scene.at("materials").at("pane").at("ior").get<double>(), 1.5 / air, 1e-12);
  EXPECT_FALSE(has_warning(thin, "one-sided")) << warnings_of(thin);
  EXPECT_TRUE(error_is(
      import_error("ior.xml", scene3(R"(<bsdf type="dielectric"><string name="int_ior" value="unobtainium"/></bsdf>)")),
      path_of("ior.xml") + ":3: ", "unknown index of refraction \"unobtainium\""));
}

TEST(MitsubaImport, ConductorsBecomeMirrorsAndRoughConductors) {
  ImportedScene s =
      import_file("metal.xml", scene3(R"(<bsdf type="twosided" id="perfect"><bsdf type="conductor"/></bsdf>
<bsdf type="twosided" id="gold"><bsdf type="conductor"><string name="material" value="Au"/></bsdf></bsdf>
<bsdf type="twosided" id="rough"><bsdf type="roughconductor"><string name="material" value="Cu"/><float name="alpha" value="0.04"/>
  <string name="distribution" value="ggx"/></bsdf></bsdf>
<bsdf type="twosided" id="beckmann"><bsdf type="roughconductor"><rgb name="eta" value="0.2 0.9 1.1"/><rgb name="k" value="3 2.5 2.2"/></bsdf></bsdf>
<bsdf type="twosided" id="smoothest"><bsdf type="roughconductor"><float name="alpha" value="0"/><string name="distribution" value="ggx"/></bsdf></bsdf>)"));
  const json& m = s.scene.at("materials");
  EXPECT_EQ(m.at("perfect"), (json{{"type", "mirror"}, {"reflectance", {1.0, 1.0, 1.0}}}));  // Mitsuba's "none": exact
  // Any other conductor: pathcl's mirror with eta and k reflects the same Fresnel term at every angle.
  glm::dvec3 eta, k;
  ASSERT_TRUE(named_conductor("Au", &eta, &k));
  EXPECT_EQ(m.at("gold").at("type"), "mirror");
  expect_vec(m.at("gold").at("reflectance"), {1, 1, 1});
  expect_vec(m.at("gold").at("eta"), eta, 1e-12);
  expect_vec(m.at("gold").at("k"), k, 1e-12);
  ASSERT_TRUE(named_conductor("Cu", &eta, &k));
  EXPECT_EQ(m.at("rough").at("type"), "rough_conductor");
  EXPECT_NEAR(m.at("rough").at("roughness").get<double>(), 0.2, 1e-12);  // sqrt(alpha)
  expect_vec(m.at("rough").at("eta"), eta, 1e-12);
  expect_vec(m.at("rough").at("k"), k, 1e-12);
  expect_vec(m.at("beckmann").at("eta"), {0.2, 0.9, 1.1});
  EXPECT_NEAR(m.at("beckmann").at("roughness").get<double>(), std::sqrt(0.1), 1e-12);  // Mitsuba's default alpha
  EXPECT_TRUE(has_warning(s, "the Beckmann microfacet distribution becomes GGX")) << warnings_of(s);
  EXPECT_EQ(m.at("smoothest").at("roughness"), 0.01);
  EXPECT_TRUE(has_warning(s, "is clamped to pathcl's range of roughness")) << warnings_of(s);
  expect_vec(m.at("smoothest").at("specular"), {1, 1, 1});  // "none": as near a perfect conductor as pathcl goes
}

// Mitsuba 3.9's smooth plastic evaluated at normal incidence (mi.load_dict({'type': 'plastic', ...}).eval)
// divided by (1 - F(0))^2 / pi: the diffuse pathcl's plastic needs to reflect the same.
TEST(MitsubaImport, PlasticDiffuseIsScaledToMitsubasLobe) {
  ImportedScene s = import_file(
      "plastic.xml",
      scene3(
          R"(<bsdf type="twosided" id="linear"><bsdf type="plastic"><rgb name="diffuse_reflectance" value="0.5 0.2 0.9"/></bsdf></bsdf>
<bsdf type="twosided" id="nonlinear"><bsdf type="plastic"><rgb name="diffuse_reflectance" value="0.5 0.2 0.9"/><boolean name="nonlinear" value="true"/></bsdf></bsdf>
<bsdf type="twosided" id="bright"><bsdf type="plastic"><rgb name="diffuse_reflectance" value="0.95"/></bsdf></bsdf>
<bsdf type="twosided" id="rough"><bsdf type="roughplastic"><float name="alpha" value="0.09"/><string name="distribution" value="ggx"/></bsdf></bsdf>)"));
  const json& m = s.scene.at("materials");
  EXPECT_EQ(m.at("linear").at("type"), "plastic");
  EXPECT_NEAR(m.at("linear").at("ior").get<double>(), 1.48958738, 1e-6);  // polypropylene / air
  expect_vec(m.at("linear").at("diffuse"), {0.5502521611, 0.2201008695, 0.9904537988}, 1e-6);
  expect_vec(m.at("nonlinear").at("diffuse"), {0.3197396140, 0.1022060530, 0.8656393946}, 1e-6);
  expect_vec(m.at("bright").at("diffuse"), {1, 1, 1});
  EXPECT_TRUE(has_warning(s, "exceeds 1 and is clamped to 1")) << warnings_of(s);
  EXPECT_EQ(m.at("rough").at("type"), "plastic");
  EXPECT_NEAR(m.at("rough").at("roughness").get<double>(), 0.3, 1e-12);
  EXPECT_TRUE(has_warning(s, "Mitsuba's rough plastic transmits into its base by tabulated rough-coat terms"))
      << warnings_of(s);
}

TEST(MitsubaImport, MaskBumpmapPhongAndNull) {
  ImportedScene s = import_file("wrappers.xml", R"(<scene version="0.6.0">
<sensor type="perspective"/>
<bsdf type="mask" id="leaf"><spectrum name="opacity" value="0.3"/><bsdf type="twosided"><bsdf type="diffuse"/></bsdf></bsdf>
<bsdf type="twosided" id="bumpy"><bsdf type="bumpmap"><texture type="bitmap"><string name="filename" value="bump.png"/></texture>
  <bsdf type="diffuse"><rgb name="reflectance" value="0.1 0.2 0.3"/></bsdf></bsdf></bsdf>
<bsdf type="twosided" id="phong"><bsdf type="phong"><float name="exponent" value="50"/><rgb name="specularReflectance" value="0.3"/></bsdf></bsdf>
<bsdf type="null" id="nothing"/>
</scene>)");
  const json& m = s.scene.at("materials");
  EXPECT_EQ(m.at("leaf"), (json{{"type", "diffuse"}, {"reflectance", {0.5, 0.5, 0.5}}, {"opacity", 0.3}}));
  expect_vec(m.at("bumpy").at("reflectance"), {0.1, 0.2, 0.3});
  EXPECT_TRUE(has_warning(s, "the bumpmap is ignored")) << warnings_of(s);
  EXPECT_EQ(m.at("phong"),
            (json{{"type", "phong"}, {"diffuse", {0.5, 0.5, 0.5}}, {"specular", {0.3, 0.3, 0.3}}, {"exponent", 50.0}}));
  EXPECT_EQ(m.at("nothing"), (json{{"type", "diffuse"}, {"reflectance", {0.0, 0.0, 0.0}}, {"opacity", 0}}));
  EXPECT_TRUE(error_is(import_error("hair.xml", scene3(R"(<bsdf type="hair"/>)")),
                       path_of("hair.xml") + ":3: ", "bsdf \"hair\" is not supported (supported: diffuse, dielectric"));
}

// ---------------------------------------------------------------------------------------------------
// Checkerboard textures

// The checkerboard of a diffuse material's JSON.
const json& checker_of(const ImportedScene& s, const std::string& material, const std::string& key = "reflectance") {
  return s.scene.at("materials").at(material).at(key).at("checkerboard");
}

glm::dvec2 pair_of(const json& j, const std::string& key, glm::dvec2 fallback) {
  if (!j.contains(key)) return fallback;
  return {j.at(key).at(0).get<double>(), j.at(key).at(1).get<double>()};
}

TEST(MitsubaImport, CheckerboardBecomesPathclsCheckerboard) {
  ImportedScene s = import_file("checker.xml", scene3(R"(<texture type="checkerboard" id="planetex">
  <rgb name="color0" value="0.2"/><rgb name="color1" value="0.4"/>
  <transform name="to_uv"><matrix value="8 0 0 0 0 8 0 0 0 0 8 0 0 0 0 1"/></transform></texture>
<bsdf type="twosided" id="plane"><bsdf type="diffuse"><ref name="reflectance" id="planetex"/></bsdf></bsdf>
<bsdf type="twosided" id="defaults"><bsdf type="diffuse"><texture type="checkerboard" name="reflectance"/></bsdf></bsdf>
<bsdf type="twosided" id="moved"><bsdf type="diffuse"><texture type="checkerboard" name="reflectance">
  <spectrum name="color0" value="0.7"/><float name="color1" value="0.1"/>
  <transform name="to_uv"><scale x="1.5" y="2.5"/><translate x="0.1" y="-0.35"/></transform></texture></bsdf></bsdf>
<bsdf type="twosided" id="bright"><bsdf type="diffuse"><texture type="checkerboard" name="reflectance">
  <rgb name="color0" value="1.5 0.5 0.25"/><string name="colour" value="x"/></texture></bsdf></bsdf>
<bsdf type="twosided" id="rotated"><bsdf type="diffuse"><texture type="checkerboard" name="reflectance">
  <transform name="to_uv"><rotate z="1" angle="30"/><scale x="3"/></transform></texture></bsdf></bsdf>
<bsdf type="twosided" id="glass"><bsdf type="dielectric"><texture type="checkerboard" name="specular_transmittance"/></bsdf></bsdf>
<bsdf type="twosided" id="plastic"><bsdf type="plastic"><texture type="checkerboard" name="diffuse_reflectance">
  <float name="color0" value="0.5"/><float name="color1" value="0.9"/></texture></bsdf></bsdf>
<bsdf type="twosided" id="nonlinear"><bsdf type="plastic"><boolean name="nonlinear" value="true"/>
  <texture type="checkerboard" name="diffuse_reflectance"><float name="color0" value="0.5"/><float name="color1" value="0.9"/></texture></bsdf></bsdf>
<bsdf type="twosided" id="phong"><bsdf type="phong"><float name="specular_reflectance" value="0.5"/>
  <texture type="checkerboard" name="diffuse_reflectance"><float name="color0" value="0.3"/><float name="color1" value="0.75"/></texture></bsdf></bsdf>
<bsdf type="mask" id="leaf"><texture type="checkerboard" name="opacity"><rgb name="color0" value="0.9 0.6 0.3"/><float name="color1" value="1.5"/></texture>
  <bsdf type="twosided"><bsdf type="diffuse"/></bsdf></bsdf>
<shape type="rectangle"><ref id="plane"/></shape>)"));
  // matpreview.xml's plane: a 4 x 4 to_uv of scale 8 gives 16 tiles a unit.
  EXPECT_EQ(checker_of(s, "plane"),
            (json{{"color0", {0.2, 0.2, 0.2}}, {"color1", {0.4, 0.4, 0.4}}, {"tiles", {16.0, 16.0}}}));
  EXPECT_EQ(checker_of(s, "defaults"),
            (json{{"color0", {0.4, 0.4, 0.4}}, {"color1", {0.2, 0.2, 0.2}}, {"tiles", {2.0, 2.0}}}));
  // Scale then translate: s = 1.5 u + 0.1, 2.5 v - 0.35: tiles 3 and 5, offsets 0.2 and -0.7 + 2 tiles.
  const json& moved = checker_of(s, "moved");
  expect_vec(moved.at("color0"), glm::dvec3(0.7));  // a uniform reflectance spectrum is grey
  expect_vec(moved.at("color1"), glm::dvec3(0.1));
  EXPECT_EQ(moved.at("tiles"), (json{3.0, 5.0}));
  EXPECT_NEAR(moved.at("offset")[0].get<double>(), 0.2, 1e-12);
  EXPECT_NEAR(moved.at("offset")[1].get<double>(), 1.3, 1e-12);
  expect_vec(checker_of(s, "bright").at("color0"), {1, 0.5, 0.25});
  EXPECT_TRUE(has_warning(s, "reflectance (1.5, 0.5, 0.25) is clamped into [0, 1]")) << warnings_of(s);
  EXPECT_TRUE(has_warning(s, "texture \"checkerboard\": parameter \"colour\" is not supported; ignored"))
      << warnings_of(s);
  // Rotated by 30 degrees, then scaled: the tiles keep their size (the rows' lengths, 3 and 1), with a warning.
  EXPECT_NEAR(checker_of(s, "rotated").at("tiles")[0].get<double>(), 6, 1e-12);
  EXPECT_NEAR(checker_of(s, "rotated").at("tiles")[1].get<double>(), 2, 1e-12);
  EXPECT_TRUE(
      has_warning(s, path_of("checker.xml") + ":14: texture \"checkerboard\": to_uv rotates or shears the pattern"))
      << warnings_of(s);
  EXPECT_TRUE(checker_of(s, "glass", "transmittance").is_object());
  // A plastic's colours are scaled as its constant diffuse is (PlasticDiffuseIsScaledToMitsubasLobe), and no
  // warning says the texture is used unscaled.
  expect_vec(checker_of(s, "plastic", "diffuse").at("color0"), glm::dvec3(0.5502521611), 1e-6);
  expect_vec(checker_of(s, "plastic", "diffuse").at("color1"), glm::dvec3(0.9904537988), 1e-6);
  expect_vec(checker_of(s, "nonlinear", "diffuse").at("color0"), glm::dvec3(0.3197396140), 1e-6);
  expect_vec(checker_of(s, "nonlinear", "diffuse").at("color1"), glm::dvec3(0.8656393946), 1e-6);
  EXPECT_FALSE(has_warning(s, "used unscaled")) << warnings_of(s);
  // A phong's larger colour plus specular reaches 1.25: both scaled by 1 / 1.25.
  expect_vec(checker_of(s, "phong", "diffuse").at("color0"), glm::dvec3(0.24), 1e-12);
  expect_vec(checker_of(s, "phong", "diffuse").at("color1"), glm::dvec3(0.6), 1e-12);
  expect_vec(s.scene.at("materials").at("phong").at("specular"), glm::dvec3(0.4), 1e-12);
  EXPECT_TRUE(has_warning(s, "diffuse + specular reflectance reaches 1.25")) << warnings_of(s);
  // A mask reads Mitsuba's eval_1, whose colours are the other way round: color0 becomes the mean of color1
  // (1.5, clipped to 1), color1 that of color0.
  const json& leaf = checker_of(s, "leaf", "opacity");
  expect_vec(leaf.at("color0"), glm::dvec3(1));
  expect_vec(leaf.at("color1"), glm::dvec3(0.6), 1e-12);
  EXPECT_EQ(s.warnings.size(), 5u) << warnings_of(s);  // clamped, colour, rotated, phong, no integrator

  // The translation loads as a pathcl scene.
  SceneDescription scene = load_scene(path_of("checker.xml"));
  EXPECT_EQ(scene.textures.size(), 9u);
  EXPECT_EQ(scene.textures[scene.materials[0].color_texture].format, PC_TEXELS_CHECKER);

  // 0.6's names: to_uv = scale(uscale, vscale) translate(uoffset, voffset).
  ImportedScene old = import_file("checker06.xml", R"(<scene version="0.6.0"><sensor type="perspective"/>
<bsdf type="diffuse" id="c"><texture type="checkerboard" name="reflectance"><float name="uscale" value="4"/>
  <float name="uoffset" value="0.25"/><float name="vscale" value="-2"/></texture></bsdf></scene>)");
  const json& c06 = checker_of(old, "c");
  EXPECT_EQ(c06.at("tiles"), (json{8.0, 4.0}));
  EXPECT_EQ(c06.at("offset"), (json{0.0, 1.0}));  // 2 x 4 x 0.25 = 2 = 0 modulo 2; the mirrored v: 1 tile

  // Refused: a zero scale, a texture as a colour, a checkerboard where pathcl takes a constant.
  EXPECT_TRUE(error_is(import_error("flat.xml", scene3(R"(<bsdf type="diffuse"><texture type="checkerboard" name="reflectance">
  <transform name="to_uv"><scale x="0" y="1"/></transform></texture></bsdf>)")),
                       path_of("flat.xml") + ":4: ", "to_uv maps the texture coordinates onto a line or a point"));
  EXPECT_TRUE(error_is(import_error("nested.xml", scene3(R"(<bsdf type="diffuse"><texture type="checkerboard" name="reflectance">
  <texture type="checkerboard" name="color0"/></texture></bsdf>)")),
                       path_of("nested.xml") + ":4: ",
                       "color0 is a texture (pathcl's checkerboard takes two constant colours)"));
  EXPECT_TRUE(error_is(import_error("glow.xml", scene3(R"(<shape type="rectangle"><emitter type="area">
  <texture type="checkerboard" name="radiance"/></emitter></shape>)")),
                       path_of("glow.xml") + ":4: ",
                       "parameter \"radiance\" takes a constant in pathcl, not a texture"));
  EXPECT_TRUE(error_is(
      import_error("carbon.xml",
                   scene3(R"(<bsdf type="roughconductor"><texture type="checkerboard" name="alpha"/></bsdf>)")),
                       path_of("carbon.xml") + ":3: ", "alpha must be a number"));
}

// Mitsuba's rule (color0 where frac(s) > 0.5 along both axes of s = to_uv (u, v) or neither) and pathcl's (color1
// where floor(u tiles + offset) + floor((1 - v) tiles + offset) is odd), the latter read from the translation, at
// pathcl's uv of the same point, (u, 1 - v): the same colour at random points away from the tiles' edges, for to_uv
// of every kind the translation takes exactly.
TEST(MitsubaImport, CheckerboardTilesAreMitsubasOnTheSamePoints) {
  const char* to_uvs[] = {
      "",
      R"(<scale x="1.5" y="2.5"/><translate x="0.1" y="-0.35"/>)",
      R"(<scale x="-1.5" y="2"/><translate x="0.2" y="0.35"/>)",
      R"(<scale x="3" y="-0.75"/><translate x="-2.3" y="0.6"/>)",
      R"(<scale x="1.5" y="3"/><rotate z="1" angle="90"/><translate x="0.1" y="0.2"/>)",
      R"(<rotate z="1" angle="-90"/><scale x="0.7" y="1.3"/><translate x="0.45" y="0.05"/>)",
      R"(<rotate z="1" angle="180"/><translate x="0.3" y="0.3"/>)",
      R"(<matrix value="0 -2 0 0.125  5 0 0 -1.5  0 0 1 0  0 0 0 1"/>)",
  };
  for (const char* to_uv : to_uvs) {
    const std::string xml = scene3(std::string(R"(<bsdf type="twosided" id="c"><bsdf type="diffuse"><texture type="checkerboard" name="reflectance">
  <transform name="to_uv">)") + to_uv + "</transform></texture></bsdf></bsdf>");
    ImportedScene s = import_file("checker-points.xml", xml);
    EXPECT_EQ(s.warnings.size(), 1u) << to_uv << "\n" << warnings_of(s);  // no integrator: exact
    const json& c = checker_of(s, "c");
    const glm::dvec2 tiles = pair_of(c, "tiles", {2, 2}), offset = pair_of(c, "offset", {0, 0});
    // Mitsuba's to_uv, read here by a reader of its own for these four operations, each applied after the ones
    // before it as Mitsuba composes them.
    glm::dmat4 m(1.0);
    const std::string ops = to_uv;
    for (size_t at = ops.find('<'); at != std::string::npos; at = ops.find('<', at + 1)) {
      size_t end = ops.find("/>", at);
      std::string op = ops.substr(at + 1, end - at - 1);
      auto attr = [&](const std::string& name, double fallback) {
        size_t k = op.find(" " + name + "=\"");
        return k == std::string::npos ? fallback : std::stod(op.substr(k + name.size() + 3));
      };
      glm::dmat4 step(1.0);
      if (op.rfind("scale", 0) == 0) step = glm::scale(glm::dmat4(1.0), {attr("x", 1), attr("y", 1), attr("z", 1)});
      if (op.rfind("translate", 0) == 0)
        step = glm::translate(glm::dmat4(1.0), {attr("x", 0), attr("y", 0), attr("z", 0)});
      if (op.rfind("rotate", 0) == 0)
        step = glm::rotate(glm::dmat4(1.0), glm::radians(attr("angle", 0)),
                           glm::dvec3(attr("x", 0), attr("y", 0), attr("z", 0)));
      if (op.rfind("matrix", 0) == 0) {
        std::istringstream values(op.substr(op.find('"') + 1));
        for (int r = 0; r < 4; ++r)
          for (int col = 0; col < 4; ++col) values >> step[col][r];
      }
      m = step * m;
    }
    std::mt19937 gen(3);
    std::uniform_real_distribution<double> coordinate(-2, 2);
    int compared = 0;
    for (int i = 0; i < 4000; ++i) {
      const double u = coordinate(gen), v = coordinate(gen);  // Mitsuba's uv
      const double su = m[0][0] * u + m[1][0] * v + m[3][0], sv = m[0][1] * u + m[1][1] * v + m[3][1];
      const double x = u * tiles.x + offset.x, y = (1 - (1 - v)) * tiles.y + offset.y;  // pathcl's v is 1 - v
      auto near_edge = [](double t) { return std::abs(t - std::round(t)) < 1e-6; };
      if (near_edge(2 * su) || near_edge(2 * sv) || near_edge(x) || near_edge(y)) continue;
      ++compared;
      const bool mitsuba_color1 = (su - std::floor(su) > 0.5) != (sv - std::floor(sv) > 0.5);
      const bool pathcl_color1 = (long long)(std::floor(x) + std::floor(y)) % 2 != 0;
      ASSERT_EQ(pathcl_color1, mitsuba_color1) << to_uv << " at Mitsuba's uv (" << u << ", " << v << ")";
    }
    EXPECT_GT(compared, 3900) << to_uv;
  }
}

// ---------------------------------------------------------------------------------------------------
// Cylinders

TEST(MitsubaImport, CylinderBecomesASmoothTubeOfTheCylindersArea) {
  ImportedScene s = import_file("cylinders.xml", scene3(R"(<shape type="cylinder"/>
<shape type="cylinder"><float name="radius" value="0.5"/><point name="p0" x="1" y="2" z="3"/><point name="p1" x="1.5" y="2.3" z="4.4"/>
  <transform name="to_world"><translate x="10"/></transform></shape>
<shape type="cylinder"><boolean name="flip_normals" value="true"/></shape>
<shape type="cylinder"><float name="radius" value="-1"/></shape>)"));
  const json& shapes = s.scene.at("shapes");
  ASSERT_EQ(shapes.size(), 4u);
  const double ring = M_PI / (128 * std::sin(M_PI / 128));  // the perimeter of 128 chords is 2 pi
  struct Face {
    glm::dvec3 normal, centroid;  // cross(b - a, c - a), the front side's
  };
  auto faces = [](const json& shape) {
    std::vector<Face> out;
    for (const json& f : shape.at("indices")) {
      glm::dvec3 a = vec(shape.at("positions")[f[0].get<int>()]), b = vec(shape.at("positions")[f[1].get<int>()]),
                 c = vec(shape.at("positions")[f[2].get<int>()]);
      out.push_back({glm::cross(b - a, c - a), (a + b + c) / 3.0});
    }
    return out;
  };

  // The unit cylinder: 2 rings of 129 vertices (the seam twice), 256 triangles, facing outwards, area 2 pi.
  const json& unit = shapes[0];
  EXPECT_EQ(unit.at("type"), "triangles");
  ASSERT_EQ(unit.at("positions").size(), 258u);
  ASSERT_EQ(unit.at("indices").size(), 256u);
  EXPECT_EQ(unit.at("smooth"), true);
  EXPECT_EQ(unit.at("smooth_angle_degrees"), 30);
  EXPECT_FALSE(unit.contains("transform"));
  for (size_t i = 0; i < 258; ++i) {
    glm::dvec3 p = vec(unit.at("positions")[i]);
    const int k = int(i % 129), z = int(i / 129);
    EXPECT_NEAR(std::hypot(p.x, p.y), ring, 1e-12) << i;
    EXPECT_EQ(p.z, double(z)) << i;
    EXPECT_NEAR(std::atan2(p.y, p.x), std::remainder(2 * M_PI * k / 128, 2 * M_PI), 1e-12) << i;
    // Mitsuba's uv (angle / 2 pi, z), its v flipped into pathcl's.
    EXPECT_EQ(unit.at("uvs")[i], (json{double(k) / 128, 1.0 - z})) << i;
  }
  double area = 0;
  for (const Face& f : faces(unit)) {
    EXPECT_GT(glm::dot(f.normal, glm::dvec3(f.centroid.x, f.centroid.y, 0)), 0);  // outward
    area += glm::length(f.normal) / 2;
  }
  EXPECT_NEAR(area, 2 * M_PI, 1e-9);
  EXPECT_TRUE(has_warning(s, path_of("cylinders.xml") +
                                 ":3: shape \"cylinder\": tessellated into 256 triangles (128 segments, shaded smooth), "
                                 "their rings' radius scaled by 1.0001 so that the area is the cylinder's"))
      << warnings_of(s);

  // Radius 0.5 from p0 to p1, then moved by to_world: Mitsuba's vertices at uv (0, 0), (0.25, 0) and (0.5, 1)
  // (its to_world applied to (cos 2 pi u, sin 2 pi u, v), from Mitsuba 3.9.1), the ring scaled by 1.0001.
  const json& placed = shapes[1];
  expect_matrix(placed.at("transform"), glm::translate(glm::dmat4(1.0), {10, 0, 0}));
  const glm::dvec3 p0(1, 2, 3), p1(1.5, 2.3, 4.4), axis = glm::normalize(p1 - p0);
  auto mitsuba_vertex = [&](glm::dvec3 at_ring_1, glm::dvec3 centre) { return centre + ring * (at_ring_1 - centre); };
  expect_vec(placed.at("positions")[0], mitsuba_vertex({1.47174, 1.98304, 2.83515}, p0), 2e-5);
  expect_vec(placed.at("positions")[32], mitsuba_vertex({0.983044, 2.48983, 2.90109}, p0), 2e-5);
  expect_vec(placed.at("positions")[129 + 64], mitsuba_vertex({1.02826, 2.31696, 4.56485}, p1), 2e-5);
  area = 0;
  for (const Face& f : faces(placed)) {
    glm::dvec3 radial = f.centroid - p0 - glm::dot(f.centroid - p0, axis) * axis;
    EXPECT_GT(glm::dot(f.normal, radial), 0);
    area += glm::length(f.normal) / 2;
  }
  EXPECT_NEAR(area, 2 * M_PI * 0.5 * glm::length(p1 - p0), 1e-9);
  for (size_t i = 0; i < 258; ++i) {
    glm::dvec3 d = vec(placed.at("positions")[i]) - p0;
    EXPECT_NEAR(glm::length(d - glm::dot(d, axis) * axis), 0.5 * ring, 1e-12) << i;
  }

  // flip_normals: every face inward.
  for (const Face& f : faces(shapes[2])) EXPECT_LT(glm::dot(f.normal, glm::dvec3(f.centroid.x, f.centroid.y, 0)), 0);
  // A negative radius: the same tube turned by 180 degrees (u = 0 at -x), still facing outwards.
  expect_vec(shapes[3].at("positions")[0], {-ring, 0, 0}, 1e-12);
  for (const Face& f : faces(shapes[3])) EXPECT_GT(glm::dot(f.normal, glm::dvec3(f.centroid.x, f.centroid.y, 0)), 0);

  // It loads, as an emitter too.
  const std::string path = write_temp_file("mitsuba/cylinder-load.xml", scene3(R"(<shape type="cylinder"><emitter type="area"/></shape>
<shape type="cylinder"><float name="radius" value="2"/><bsdf type="twosided"><bsdf type="diffuse"><texture type="checkerboard" name="reflectance"/></bsdf></bsdf></shape>)"));
  SceneDescription scene = load_scene(path);
  EXPECT_EQ(scene.shapes.size(), 2u);

  EXPECT_TRUE(error_is(import_error("thin.xml", scene3(R"(<shape type="cylinder"><float name="radius" value="0"/></shape>)")),
                       path_of("thin.xml") + ":3: ", "shape \"cylinder\": expected a radius other than 0"));
  EXPECT_TRUE(error_is(import_error("short.xml", scene3(R"(<shape type="cylinder"><point name="p1" x="0" y="0" z="0"/></shape>)")),
                       path_of("short.xml") + ":3: ", "p0 and p1 coincide"));
}

// ---------------------------------------------------------------------------------------------------
// The file structure: 0.6 names, defaults, includes, references

TEST(MitsubaImport, Version06NamesAreUpgraded) {
  ImportedScene s = import_file("old.xml", R"(<scene version="0.6.0">
  <integrator type="path"><integer name="maxDepth" value="3"/></integrator>
  <sensor type="perspective">
    <float name="fov" value="30"/><string name="fovAxis" value="y"/>
    <transform name="toWorld"><lookAt origin="0, 0, 5" target="0, 0, 0" up="0, 1, 0"/></transform>
    <sampler type="independent"><integer name="sampleCount" value="8"/></sampler>
    <film type="hdrfilm"><integer name="width" value="200"/><integer name="height" value="100"/></film>
  </sensor>
  <bsdf type="dielectric" id="glass"><float name="intIOR" value="1.6"/><float name="extIOR" value="1.2"/></bsdf>
  <bsdf type="twosided" id="grey"><bsdf type="diffuse"><srgb name="diffuseReflectance" value="#808080"/></bsdf></bsdf>
  <shape type="sphere"><float name="radius" value="2"/><ref id="glass"/></shape>
</scene>)");
  EXPECT_EQ(s.scene.at("render").at("max_depth"), 2);
  EXPECT_EQ(s.scene.at("render").at("spp"), 8);
  EXPECT_NEAR(s.scene.at("camera").at("fov_y_degrees").get<double>(), 30, 1e-9);
  expect_vec(s.scene.at("camera").at("position"), {0, 0, 5});
  EXPECT_NEAR(s.scene.at("materials").at("glass").at("ior").get<double>(), 1.6 / 1.2, 1e-12);
  const double grey = std::pow((128 / 255.0 + 0.055) / 1.055, 2.4);  // 0.6's <srgb> is gamma-encoded
  expect_vec(s.scene.at("materials").at("grey").at("reflectance"), glm::dvec3(grey), 1e-12);
  EXPECT_EQ(s.warnings.size(), 0u) << warnings_of(s);
}

TEST(MitsubaImport, DefaultsAreSubstituted) {
  ImportedScene s = import_file("defaults.xml", R"(<scene version="3.0.0">
  <default name="spp" value="32"/>
  <default name="spp" value="64"/>
  <default name="res" value="100"/>
  <default name="resolution" value="50"/>
  <sensor type="perspective">
    <sampler type="independent"><integer name="sample_count" value="$spp"/></sampler>
    <film type="hdrfilm"><integer name="width" value="$resolution"/><integer name="height" value="$res"/></film>
  </sensor>
  <integrator type="path"/>
</scene>)");
  EXPECT_EQ(s.scene.at("render").at("spp"), 32);    // the first <default> of a name counts
  EXPECT_EQ(s.scene.at("camera").at("width"), 50);  // the longest name first
  EXPECT_EQ(s.scene.at("camera").at("height"), 100);
  EXPECT_TRUE(error_is(
      import_error("undefined.xml",
                   scene3(R"(<integrator type="path"><integer name="max_depth" value="$depth"/></integrator>)")),
      path_of("undefined.xml") + ":3: ", "undefined parameter $depth"));
}

TEST(MitsubaImport, IncludesNestAndUpgradeEachFileByItsVersion) {
  write_temp_file("mitsuba/inc/parts/materials.xml", R"(<scene version="3.0.0">
  <bsdf type="twosided" id="red"><bsdf type="diffuse"><rgb name="reflectance" value="0.8 0.1 0.1"/></bsdf></bsdf>
  <include filename="more.xml"/>
</scene>)");
  write_temp_file("mitsuba/inc/parts/more.xml", R"(<scene version="0.6.0">
  <bsdf type="twosided" id="blue"><bsdf type="diffuse"><rgb name="diffuseReflectance" value="0.1 0.1 0.8"/></bsdf></bsdf>
</scene>)");
  write_temp_file("mitsuba/inc/parts/bsdf.xml",
                  R"(<bsdf version="3.0.0" type="twosided" id="green"><bsdf type="diffuse"/></bsdf>)");
  ImportedScene s = import_file("inc/main.xml", scene3(R"(<include filename="parts/materials.xml"/>
<shape type="sphere"><ref id="red"/></shape>
<shape type="rectangle"><include filename="parts/bsdf.xml"/></shape>)"));
  const json& m = s.scene.at("materials");
  expect_vec(m.at("red").at("reflectance"), {0.8, 0.1, 0.1});
  expect_vec(m.at("blue").at("reflectance"), {0.1, 0.1, 0.8});
  EXPECT_TRUE(m.contains("green"));
  EXPECT_EQ(s.scene.at("shapes")[0].at("material"), "red");
  EXPECT_EQ(s.scene.at("shapes")[1].at("material"), "green");
  EXPECT_EQ(origin_of(s, "materials.blue").rfind(temp_dir() + "/mitsuba/inc/parts/more.xml:2: ", 0), 0u)
      << origin_of(s, "materials.blue");

  EXPECT_TRUE(error_is(import_error("missing.xml", scene3(R"(<include filename="nothere.xml"/>)")),
                       path_of("missing.xml") + ":3: ",
                       "<include filename=\"nothere.xml\">: cannot open the included file " + path_of("nothere.xml") +
                           ": no such file"));
  write_temp_file("mitsuba/cycle/b.xml", "<scene version=\"3.0.0\">\n  <include filename=\"a.xml\"/>\n</scene>\n");
  EXPECT_TRUE(error_is(import_error("cycle/a.xml", scene3(R"(<include filename="b.xml"/>)")),
                       path_of("cycle/b.xml") + ":2: ", "an include cycle"));
}

TEST(MitsubaImport, ReferencesResolveByIdInAnyOrder) {
  ImportedScene s = import_file("refs.xml", scene3(R"(<shape type="sphere"><ref name="bsdf" id="later"/></shape>
<texture type="bitmap" id="tex"><string name="filename" value="t.png"/></texture>
<bsdf type="twosided" id="later"><bsdf type="diffuse"><ref name="reflectance" id="tex"/></bsdf></bsdf>)"));
  EXPECT_EQ(s.scene.at("shapes")[0].at("material"), "later");
  EXPECT_EQ(s.scene.at("materials").at("later").at("reflectance"), (json{{"texture", "t.png"}, {"wrap", "repeat"}}));
  EXPECT_TRUE(has_warning(s, "pathcl's sphere has texture coordinates of its own")) << warnings_of(s);
  EXPECT_TRUE(error_is(import_error("badref.xml", scene3(R"(<shape type="sphere">
<ref id="nobody"/></shape>)")),
                       path_of("badref.xml") + ":4: ", "<ref id=\"nobody\">: no object has this id"));
  EXPECT_TRUE(error_is(import_error("dupid.xml", scene3(R"(<bsdf type="diffuse" id="a"/>
<bsdf type="diffuse" id="a"/>)")),
                       path_of("dupid.xml") + ":4: ", "duplicate id \"a\" (first at " + path_of("dupid.xml") + ":3)"));
}

TEST(MitsubaImport, BadInputNamesFileAndLine) {
  EXPECT_TRUE(
      error_is(import_error("malformed.xml", "<scene version=\"3.0.0\">\n<sensor type=\"perspective\">\n</scene>\n"),
               path_of("malformed.xml") + ":3: ", "malformed XML: "));
  EXPECT_TRUE(error_is(import_error("noversion.xml", "<scene>\n</scene>\n"),
                       path_of("noversion.xml") + ":1: ", "<scene> has no version attribute"));
  EXPECT_TRUE(error_is(
      import_error("number.xml", scene3(R"(<shape type="sphere"><float name="radius" value="wide"/></shape>)")),
      path_of("number.xml") + ":3: ", "could not parse \"wide\" as a number"));
  EXPECT_TRUE(error_is(import_error("element.xml", scene3("\n<colour name=\"x\" value=\"1\"/>")),
                       path_of("element.xml") + ":4: ", "unknown element <colour>"));
  EXPECT_TRUE(
      error_is(import_error("kind.xml", scene3(R"(<shape type="sphere"><string name="radius" value="1"/></shape>)")),
               path_of("kind.xml") + ":3: ", "parameter \"radius\" is a <string>, expected a <float>"));
  EXPECT_TRUE(error_is(import_error("shape.xml", scene3(R"(<shape type="linearcurve"/>)")),
                       path_of("shape.xml") + ":3: ", "shape \"linearcurve\" is not supported (supported: obj, ply"));
  EXPECT_TRUE(error_is(import_error("medium.xml", scene3(R"(<medium type="homogeneous" id="fog"/>)")),
                       path_of("medium.xml") + ":3: ", "media are not supported"));
  EXPECT_TRUE(error_is(import_error("cycle.xml", scene3(R"(<bsdf type="twosided" id="a"><ref id="a"/></bsdf>)")),
                       path_of("cycle.xml") + ":3: ", "objects nested more than 64 deep (a cycle of references?)"));
  EXPECT_TRUE(error_is(import_error("nosensor.xml", "<scene version=\"3.0.0\"/>"),
                       path_of("nosensor.xml") + ":1: ", "the scene has no <sensor>"));
  ImportedScene unknown =
      import_file("unknown.xml", scene3(R"(<shape type="sphere"><rgb name="colour" value="1"/></shape>)"));
  EXPECT_TRUE(has_warning(
      unknown, path_of("unknown.xml") + ":3: shape \"sphere\": parameter \"colour\" is not supported; ignored"))
      << warnings_of(unknown);
}

// ---------------------------------------------------------------------------------------------------
// The Cornell box

TEST(MitsubaImport, CornellBoxImports) {
  const std::string path = std::string(PATHCL_TEST_SCENES) + "/mitsuba/cbox.xml";
  ImportedScene s = import_mitsuba_xml(path, read_text_file(path));
  EXPECT_EQ(s.warnings.size(), 0u) << warnings_of(s);
  const json& c = s.scene.at("camera");
  EXPECT_NEAR(c.at("fov_y_degrees").get<double>(), 40, 1e-9);  // fov_axis smaller on a square film
  EXPECT_EQ(c.at("width"), 64);
  EXPECT_EQ(c.at("filter").at("type"), "gaussian");
  EXPECT_EQ(s.scene.at("render"),
            (json{{"spp", 64}, {"seed", 1}, {"sampler", "independent"}, {"integrator", "path"}, {"max_depth", 8}}));
  const json& shapes = s.scene.at("shapes");
  ASSERT_EQ(shapes.size(), 6u);
  EXPECT_EQ(shapes[5].at("file"), "../../../scenes/meshes/cbox-light.obj");
  expect_vec(shapes[5].at("emission"), emission_spectrum_to_srgb({400, 500, 600, 700}, {0, 8, 15.6, 18.4}));
  glm::dvec3 red = vec(s.scene.at("materials").at("red").at("reflectance"));
  EXPECT_GT(red.x, 4 * red.y);
  EXPECT_EQ(origin_of(s, "shapes[1]"), path + ":57: shape \"obj\" (id \"leftwall\")");
}

TEST(MitsubaImport, CornellBoxLoadsAsAPathclScene) {
  SceneDescription scene = load_scene(std::string(PATHCL_TEST_SCENES) + "/mitsuba/cbox.xml");
  EXPECT_EQ(scene.shapes.size(), 6u);
  EXPECT_EQ(scene.materials.size(), 4u);
  EXPECT_EQ(scene.camera.width, 64);
}

// The shapes and lights the importer writes itself pass pathcl's checks as they are, in memory (integers
// unsigned, as a parsed file holds them).
TEST(MitsubaImport, GeneratedShapesAndLightsLoad) {
  const std::string path = write_temp_file(
      "mitsuba/generated.xml", scene3(R"(<integrator type="path"><integer name="max_depth" value="3"/></integrator>
<shape type="rectangle"><boolean name="flip_normals" value="true"/><emitter type="area"/></shape>
<shape type="cube"><bsdf type="twosided"><bsdf type="plastic"/></bsdf></shape>
<shape type="disk"><bsdf type="conductor"><string name="material" value="Ag"/></bsdf></shape>
<shape type="sphere"><bsdf type="roughconductor"/></shape>
<emitter type="spot"/>
<emitter type="constant"/>)"));
  SceneDescription scene = load_scene(path);
  EXPECT_EQ(scene.shapes.size(), 4u);
  EXPECT_EQ(scene.materials.size(), 4u);
  EXPECT_EQ(scene.lights.size(), 2u);
  EXPECT_EQ(scene.render.max_depth, 2u);
}
