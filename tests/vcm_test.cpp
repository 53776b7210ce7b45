// Photon merging (`vcm`, `bpm`, `sppm`; kernels/vcm.cl): exact on the cap sphere (uniform irradiance, where
// merging is unbiased at any radius), exact on a specular-diffuse-specular scene that path tracing and BDPT
// render black, vcm without merging is bdpt bit for bit, agreement with path tracing per pixel, and the
// splat film's determinism over any split of an iteration into units. Tolerances are in standard errors.
#include <cmath>

#include <gtest/gtest.h>

#include "light_transport_support.h"
#include "runtime/light_transport.h"

using namespace light_transport_test;

namespace {

const char* const kMerging[] = {"vcm", "bpm", "sppm"};

Options merging(const char* integrator, uint32_t spp, uint32_t max_depth) {
  Options o;
  o.integrator = integrator;
  o.spp = spp;
  o.max_depth = max_depth;
  return o;
}

// A spot light under a mirror ceiling points up at it; the mirror throws the spot onto a diffuse floor,
// which the camera sees only in the mirror: every path is camera -> mirror -> floor -> mirror -> light
// ("SDS"), max_depth 3 leaves out the longer ones. Next-event estimation cannot reach a delta light
// through a mirror, a floor vertex of a light path cannot connect to one of a camera path on the same
// plane, and the camera sees no floor directly: path and bdpt render it black; only merging has it.
std::string sds_scene() {
  return R"({"camera": {"position": [0, 0.2, 1.0], "look_at": [0, 2, 0], "fov_y_degrees": 30, "width": 32, "height": 24},
    "materials": {"floor": {"type": "diffuse", "reflectance": [0.5, 0.5, 0.5]}, "mirror": {"type": "mirror", "reflectance": [1, 1, 1]}},
    "shapes": [
      {"type": "triangles", "positions": [[-4, 0, -4], [4, 0, -4], [4, 0, 4], [-4, 0, 4]], "indices": [[0, 2, 1], [0, 3, 2]], "material": "floor"},
      {"type": "triangles", "positions": [[-4, 2, -4], [4, 2, -4], [4, 2, 4], [-4, 2, 4]], "indices": [[0, 1, 2], [0, 2, 3]], "material": "mirror"}],
    "lights": [{"type": "spot", "position": [0, 1, 0], "direction": [0, 1, 0], "intensity": [10, 10, 10],
                "outer_angle_degrees": 60, "inner_angle_degrees": 50}]})";
}

// The same image unfolded about the mirror's plane y = 2: the floor seen from the mirrored camera (its up
// mirrored too: the image is mirrored left to right, and the scene is symmetric in x), lit directly by the
// mirrored spot. At max_depth 1 each sample is the closed form rho / pi I cos(theta) / d^2 at the pixel's
// floor point (the camera sees only the spot's inner cone, where I is constant): the exact image, up to
// the pixel filter's sampling.
std::string sds_unfolded_scene() {
  return R"({"camera": {"position": [0, 3.8, 1.0], "look_at": [0, 2, 0], "up": [0, -1, 0], "fov_y_degrees": 30, "width": 32, "height": 24},
    "materials": {"floor": {"type": "diffuse", "reflectance": [0.5, 0.5, 0.5]}},
    "shapes": [{"type": "triangles", "positions": [[-4, 0, -4], [4, 0, -4], [4, 0, 4], [-4, 0, 4]], "indices": [[0, 2, 1], [0, 3, 2]], "material": "floor"}],
    "lights": [{"type": "spot", "position": [0, 3, 0], "direction": [0, -1, 0], "intensity": [10, 10, 10],
                "outer_angle_degrees": 60, "inner_angle_degrees": 50}]})";
}

}  // namespace

// The Szirmay-Kalos cap sphere (scripts/make-cap-sphere) lit by its emitting cap has uniform irradiance
// on its wall, and a ball about a point of a sphere cuts out exactly pi r^2 of it (Archimedes): the
// density estimate of merging is unbiased at any radius there. Every wall pixel is f Le rho (1 - rho^n)
// / (1 - rho) after n reflections, for each merging integrator (the default radius, and one of a fifth of
// the sphere's radius, whose ball reaches well across the tessellation's triangles). vcm also with merging's
// factor in its MIS weights at 1 (SmallVCM's balance heuristic) besides its default: any factor must keep
// each path's weights summing to one.
TEST(Vcm, CapSphereExactForEveryMergingIntegrator) {
  std::vector<double> exact;
  DeviceScene scene = cap_sphere(&exact);
  for (const char* integrator : kMerging)
    for (uint32_t depth : {1u, 4u})
      for (double radius : {0.0, 0.2})
        for (double merge_mis : {0.0, 1.0}) {
          if (merge_mis > 0 && (std::string(integrator) != "vcm" || depth == 1u)) continue;
          Options o = merging(integrator, 64, depth);
          o.radius = radius;
          o.merge_mis = merge_mis;
          MeanStd m = seeded_mean(scene, o, 4);
          // The icosphere's tessellation bias is about 0.1 % (docs/accuracy.md): added to the tolerance.
          EXPECT_NEAR(m.mean, exact[depth], 4 * m.std_error + 2e-3 * exact[depth])
              << integrator << ", max_depth " << depth << ", radius " << radius << ", merge_mis " << merge_mis
              << ": error " << m.std_error;
          EXPECT_LT(m.std_error, 0.02 * exact[depth]) << integrator << " too noisy for the test to mean anything";
        }
}

// The SDS scene: path and bdpt give exactly 0; vcm, bpm and sppm the exact image mean (4 standard errors
// of both, seeds apart; vcm over four times the iterations, its default radius being half theirs), and
// their error falls as the radius shrinks with the iterations.
TEST(Vcm, SpecularDiffuseSpecularLightOnlyMergingSees) {
  DeviceScene scene = scene_from("vcm-sds.json", sds_scene());
  DeviceScene unfolded = scene_from("vcm-sds-unfolded.json", sds_unfolded_scene());
  Options exact_options = merging("path", 256, 1);
  const MeanStd exact = seeded_mean(unfolded, exact_options, 4);
  ASSERT_GT(exact.mean, 0.05);
  for (const char* blind : {"path", "bdpt"}) {
    Film f = render_with(scene, merging(blind, 16, 3)).film;
    EXPECT_EQ(image_mean(f), 0.0) << blind;
  }
  for (const char* integrator : kMerging) {
    MeanStd m = seeded_mean(scene, merging(integrator, std::string(integrator) == "vcm" ? 256 : 64, 3), 4);
    EXPECT_NEAR(m.mean, exact.mean, 4 * std::hypot(m.std_error, exact.std_error)) << integrator << ": error " << m.std_error;
    EXPECT_LT(m.std_error, 0.01 * exact.mean) << integrator << " too noisy for the test to mean anything";
  }
}

// On the SDS scene the error falls as the iterations grow, the radius with them: sppm's relMSE against the
// exact image (per pixel; the unfolded scene mirrored left to right, which the symmetric scene leaves the
// same) over 16 iterations and over 256. Variance falls as 1 / (i r_i^2) = i^-alpha and the squared bias
// as r_i^4 = i^(2 (alpha - 1)): at alpha 0.75 both by 4 or more over 16 times the iterations.
TEST(Vcm, ErrorFallsAsTheRadiusShrinks) {
  DeviceScene scene = scene_from("vcm-sds.json", sds_scene());
  DeviceScene unfolded = scene_from("vcm-sds-unfolded.json", sds_unfolded_scene());
  Film exact = render_with(unfolded, merging("path", 1024, 1)).film;
  auto relmse = [&](const Film& f) {
    double sum = 0;
    const uint32_t w = f.width, h = f.height;
    for (uint32_t y = 0; y < h; ++y)
      for (uint32_t x = 0; x < w; ++x)
        for (int c = 0; c < 3; ++c) {
          const double e = exact.mean[3 * (y * w + (w - 1 - x)) + c], d = f.mean[3 * (y * w + x) + c] - e;
          sum += d * d / (e * e + 1e-2);
        }
    return sum / (3.0 * w * h);
  };
  const RenderResult first = render_with(scene, merging("sppm", 16, 3));
  const double early = relmse(first.film);
  // Each light path keeps at most its one floor vertex at max_depth 3 (the mirror is a delta vertex, the
  // floor's second hit beyond the depth); most reach the floor.
  const uint64_t paths = uint64_t(first.film.width) * first.film.height * 16;
  EXPECT_LE(first.light_vertices, paths);
  EXPECT_GT(first.light_vertices, paths / 2);
  const double late = relmse(render_with(scene, merging("sppm", 256, 3)).film);
  EXPECT_LT(late, early / 4) << "relMSE " << early << " at 16 iterations, " << late << " at 256";
}

// Without merging, vcm's estimator is bdpt's (the merging factors are 0, x + 0 is x): the same bits on the
// Cornell box and glass-metal (glass, metals, a mirror).
TEST(Vcm, WithoutMergingItIsBdptBitForBit) {
  const std::string scenes = std::string(PATHCL_SOURCE_DIR) + "/scenes/";
  for (const char* name : {"cornell-box", "glass-metal"}) {
    SCOPED_TRACE(name);
    DeviceScene scene = load_device_scene(scenes + name + ".json");
    scene.header.width = 20;
    scene.header.height = 16;
    Options o = merging("vcm", 4, 5);
    o.merge = false;
    Film v = render_with(scene, o).film;
    Film b = render_with(scene, merging("bdpt", 4, 5)).film;
    ASSERT_GT(image_mean(b), 0.0);
    EXPECT_EQ(v.words, b.words);
  }
}

// Merging and path tracing estimate the same pixels: the Cornell box and glass-metal (glass, metals, a
// mirror: caustics), per channel |z| <= 4 against a longer path render. Merging's bias (light from a
// surface within the radius of an edge merged across it) shrinks with the radius: each at its default radius
// (vcm's half a pixel's footprint: its MIS gives connections the diffuse surfaces; bpm's and sppm's, which
// have nothing but merging, the whole footprint), vcm over 128 iterations, bpm and sppm over 256 (the last
// radius half the first), where a pixel gathers enough photons for its variance estimate to hold.
TEST(Vcm, AgreesWithPathTracingPerPixel) {
  const std::string scenes = std::string(PATHCL_SOURCE_DIR) + "/scenes/";
  for (const char* name : {"cornell-box", "glass-metal"}) {
    DeviceScene scene = load_device_scene(scenes + name + ".json");
    scene.header.width = 48;
    scene.header.height = 48;
    Film reference = render_with(scene, merging("path", 512, 5)).film;
    for (const char* integrator : kMerging) {
      SCOPED_TRACE(std::string(name) + ", " + integrator);
      const bool vcm = std::string(integrator) == "vcm";
      Options o = merging(integrator, vcm ? 128 : 256, 5);
      expect_same_pixels(reference, render_with(scene, o).film);
    }
  }
}

// The image is a pure function of scene, settings and seed, whichever units an iteration is split into
// (units of 37 light paths: each traces every camera path, merging with its own light vertices).
TEST(Vcm, SplatFilmIsBitwiseDeterministic) {
  DeviceScene scene = load_device_scene(std::string(PATHCL_SOURCE_DIR) + "/scenes/glass-metal.json");
  scene.header.width = 20;
  scene.header.height = 16;
  for (const char* integrator : {"vcm", "sppm"}) {
    SCOPED_TRACE(integrator);
    expect_bitwise_deterministic(scene, merging(integrator, 8, 5));
  }
}

// A work item takes 8 or 16 light paths and then 8 or 16 camera paths at once, a lane each (kernels/vcm.cl):
// every width gives the one-lane film bit for bit for vcm, bpm and sppm (one program), with every material
// and light type (light_transport_support.h). Instances and cut-outs are in the subpaths' code, which bdpt's
// test covers at every width; a merge reads only the stored vertices.
TEST(Vcm, EveryLaneWidthGivesTheOneLaneFilm) {
  for (const char* integrator : kMerging) {
    SCOPED_TRACE(integrator);
    expect_one_lane_bits_at_every_width(integrator, false);
  }
}

// A unit holds at most what the device's buffers allow (Technique::max_unit_items): on a device with 1 MiB
// allocations and 4 MiB of memory a 64 x 64 film at max_depth 8 takes units of a few hundred light paths, its
// vertices within the allocation, all buffers within a quarter of the memory; an iteration of more paths is
// split into units, whose film is the one-unit film (SplatFilmIsBitwiseDeterministic).
TEST(Vcm, UnitsFitTheDevicesMemory) {
  DeviceInfo small = test_device().info;
  small.max_alloc = 1 << 20;
  small.global_memory = 4 << 20;
  for (const char* integrator : {"bdpt", "vcm"}) {
    SCOPED_TRACE(integrator);
    const Technique& t = technique_named(integrator, "test");
    TechniqueSizes sizes{64 * 64, 8, 0, &small};
    sizes.unit_items = technique_unit_items(t, sizes);
    EXPECT_GE(sizes.unit_items, 64u);  // the probe's paths
    EXPECT_LT(sizes.unit_items, 64u * 64u);
    size_t total = 0;
    for (const TechniqueBuffer& b : t.buffers) {
      const size_t bytes = b.bytes(sizes);
      EXPECT_LE(bytes, small.max_alloc) << b.name;
      total += bytes;
    }
    EXPECT_LE(total, small.global_memory / 4);
    EXPECT_EQ(light_vertex_bytes(sizes), size_t(sizes.unit_items) * 8 * sizeof(LightVertex));
  }
}
