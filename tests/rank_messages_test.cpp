// The messages between MPI ranks (runtime/rank_messages.h), without MPI: each kind comes back as it was
// sent, and a damaged, short or long message is refused instead of trusted.
#include <gtest/gtest.h>

#include "runtime/errors.h"
#include "runtime/rank_messages.h"
#include "runtime/technique.h"
#include "test_support.h"

namespace {

const std::string kCornell = std::string(PATHCL_TEST_SCENES) + "/../../scenes/cornell-box.json";
const std::string kTextured = std::string(PATHCL_TEST_SCENES) + "/../../scenes/example.json";

// Every way of damaging a message: a flipped bit anywhere, a byte short, a byte too many.
template <class Decode>
void expect_damage_refused(const std::vector<uint8_t>& bytes, Decode&& decode) {
  for (size_t at : {size_t(0), bytes.size() / 3, bytes.size() / 2, bytes.size() - 1}) {
    std::vector<uint8_t> damaged = bytes;
    damaged[at] ^= 0x10;
    EXPECT_THROW(decode(damaged), RankMessageError) << "a flipped bit at byte " << at;
  }
  std::vector<uint8_t> shorter(bytes.begin(), bytes.end() - 1), longer = bytes;
  longer.push_back(0);
  EXPECT_THROW(decode(shorter), RankMessageError);
  EXPECT_THROW(decode(longer), RankMessageError);
  EXPECT_THROW(decode(std::vector<uint8_t>{1, 2, 3}), RankMessageError);
}

}  // namespace

TEST(RankMessages, TheDeviceSceneComesBackWhole) {
  for (const std::string& path : {kCornell, kTextured}) {
    DeviceScene scene = load_device_scene(path);
    std::vector<uint8_t> bytes = encode_scene(scene);
    DeviceScene back = decode_scene(bytes);
    EXPECT_EQ(encode_scene(back), bytes) << path;
    // A few fields by name, so that a field both directions skip would still be noticed.
    EXPECT_EQ(std::memcmp(&back.header, &scene.header, sizeof scene.header), 0);
    EXPECT_EQ(back.prims.size(), scene.prims.size());
    EXPECT_EQ(back.texels, scene.texels);
    EXPECT_EQ(back.leaf_slot, scene.leaf_slot);
    EXPECT_EQ(back.features, scene.features);
    EXPECT_EQ(back.origin, scene.origin);
    EXPECT_EQ(back.wide16_nodes, scene.wide16_nodes);
    EXPECT_EQ(back.bvh.sah_cost, scene.bvh.sah_cost);
    expect_damage_refused(bytes, [](const std::vector<uint8_t>& b) { return decode_scene(b); });
  }
}

TEST(RankMessages, SettingsUnitsAndResultsComeBack) {
  const Technique& bdpt = technique_named("bdpt", "test");
  DeviceScene scene = load_device_scene(kCornell);
  LightTransportSetup light = light_transport_setup(scene, 16);
  WorkerSettings settings;
  settings.technique = &bdpt;
  settings.layout = make_film_layout(bdpt.layers, 1u << PC_AOV_ALBEDO, 640);
  settings.build_options = "-DPC_X=1";
  settings.work_group = 32;
  settings.lanes = 8;
  settings.light = &light;
  settings.max_depth = 7;
  settings.fault.delay_seconds = 0.5;
  std::vector<uint8_t> bytes = encode_setup(scene.header, settings);
  WorkerSetupMessage m;
  decode_setup(bytes, m);
  EXPECT_EQ(m.settings.technique, &bdpt);
  EXPECT_TRUE(m.settings.layout == settings.layout);
  EXPECT_EQ(m.settings.build_options, "-DPC_X=1");
  EXPECT_EQ(m.settings.work_group, 32u);
  EXPECT_EQ(m.settings.lanes, 8u);
  EXPECT_EQ(m.settings.max_depth, 7u);
  EXPECT_EQ(m.settings.fault.delay_seconds, 0.5);
  ASSERT_EQ(m.settings.light, &m.light);
  EXPECT_EQ(m.light.emission_cdf, light.emission_cdf);
  EXPECT_EQ(std::memcmp(&m.light.header, &light.header, sizeof light.header), 0);
  expect_damage_refused(bytes, [](const std::vector<uint8_t>& b) {
    WorkerSetupMessage out;
    decode_setup(b, out);
  });

  WorkUnit unit;
  unit.id = 42;
  unit.pixel_begin = 100;
  unit.pixel_count = 3;
  unit.sample_begin = 8;
  unit.sample_count = 4;
  unit.upload = true;
  std::vector<uint32_t> input{1, 2, 3, 4, 5, 6}, got;
  bytes = encode_unit(unit, &input);
  WorkUnit back = decode_unit(bytes, got);
  EXPECT_EQ(back.id, 42u);
  EXPECT_EQ(back.pixel_begin, 100u);
  EXPECT_EQ(back.sample_count, 4u);
  EXPECT_TRUE(back.upload);
  EXPECT_EQ(got, input);
  expect_damage_refused(bytes, [](const std::vector<uint8_t>& b) {
    std::vector<uint32_t> in;
    return decode_unit(b, in);
  });

  UnitOutput out;
  out.stats.nan_samples = 3;
  out.light_vertices = 99;
  out.kernel_ms = 1.5;
  out.phases = {{"render", 1.25}, {"aov", 0.25}};
  out.ordered = {7, 8, 9};
  out.commutative = {10, 11};
  bytes = encode_output(out);
  UnitOutput o = decode_output(bytes, "rank 1");
  EXPECT_EQ(o.stats.nan_samples, 3u);
  EXPECT_EQ(o.light_vertices, 99u);
  EXPECT_EQ(o.kernel_ms, 1.5);
  ASSERT_EQ(o.phases.size(), 2u);
  EXPECT_EQ(o.phases[1].name, "aov");
  EXPECT_EQ(o.ordered, out.ordered);
  EXPECT_EQ(o.commutative, out.commutative);
  expect_damage_refused(bytes, [](const std::vector<uint8_t>& b) { return decode_output(b, "rank 1"); });

  WorkerReport report;
  report.kernel_build_ms = 12;
  report.kernel_options = "-DA";
  report.lanes = 16;
  report.buffers["light_vertices"] = 4096;
  WorkerReport r = decode_report(encode_report(report), "rank 1");
  EXPECT_EQ(r.kernel_build_ms, 12);
  EXPECT_EQ(r.kernel_options, "-DA");
  EXPECT_EQ(r.lanes, 16u);
  EXPECT_EQ(r.buffers.at("light_vertices"), 4096u);
  EXPECT_EQ(decode_probe(encode_probe(0x1234567890abcdefull), "rank 1"), 0x1234567890abcdefull);
  uint32_t count = 0, spp = 0;
  decode_probe_request(encode_probe_request(64, 4), &count, &spp);
  EXPECT_EQ(count, 64u);
  EXPECT_EQ(spp, 4u);

  RankHello hello{"node7", {{"pthread-x", "Portable Computing Language", false, true, 16, 1ull << 34}}, ""};
  RankHello h = decode_hello(encode_hello(hello));
  EXPECT_EQ(h.host, "node7");
  ASSERT_EQ(h.devices.size(), 1u);
  EXPECT_EQ(h.devices[0].name, "pthread-x");
  EXPECT_EQ(h.devices[0].compute_units, 16u);
  EXPECT_TRUE(h.devices[0].is_cpu);
}

TEST(RankMessages, AWorkersErrorIsThrownWithItsKindAndRank) {
  try {
    decode_output(encode_error("the kernel build failed", false), "rank 2 (node3) device 0");
    FAIL() << "no exception";
  } catch (const RuntimeFailure& e) {
    EXPECT_STREQ(e.what(), "rank 2 (node3) device 0: the kernel build failed");
  }
  EXPECT_THROW(decode_report(encode_error("--work-group 100000: too large", true), "rank 1"), UsageError);
}
