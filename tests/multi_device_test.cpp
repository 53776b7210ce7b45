// One image on several devices: `--device all` gives the bits of a one-device render for any unit size,
// pass size, lagging or failing device, and across a checkpoint; a device of another arithmetic class is
// left out, or used with --allow-mixed-devices. CTest runs this under POCL_DEVICES="basic pthread" and
// "pthread pthread" (tests/CMakeLists.txt), so PoCL shows two devices.
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>

#include <gtest/gtest.h>

#include "runtime/checkpoint.h"
#include "runtime/image_io.h"
#include "test_support.h"

namespace {

const std::string kCornell = std::string(PATHCL_TEST_SCENES) + "/../../scenes/cornell-box.json";

DeviceScene small_cornell() {
  DeviceScene scene = load_device_scene(kCornell);
  scene.header.width = 48;
  scene.header.height = 40;
  return scene;
}

RenderOptions base_options() {
  RenderOptions opt;
  opt.spp = 12;
  opt.max_depth = 6;
  opt.seed = 5;
  return opt;
}

std::vector<DeviceInfo> all_devices() {
  std::vector<DeviceInfo> devices = select_devices("all");
  EXPECT_GE(devices.size(), 2u) << "the test needs two devices (POCL_DEVICES)";
  return devices;
}

bool same_bits(const Film& a, const Film& b) {
  return a.words == b.words;
}

// The one-device image every multi-device render below must match.
const Film& reference_film() {
  static Film film = render({select_devices("all").front()}, small_cornell(), base_options()).film;
  return film;
}

}  // namespace

TEST(MultiDevice, AllDevicesGiveTheOneDeviceBitsForAnyUnitAndPassSize) {
  DeviceScene scene = small_cornell();
  std::vector<DeviceInfo> devices = all_devices();
  struct Split {
    uint32_t tile_pixels, max_unit_pixels, pass_spp;
  };
  // From single pixels to the whole film (1920 pixels) per unit, one or five samples per unit, or adaptive.
  for (Split split : {Split{1, 7, 1}, Split{37, 0, 5}, Split{1920, 0, 5}, Split{64, 256, 1}, Split{0, 0, 0}}) {
    RenderOptions opt = base_options();
    opt.tile_pixels = split.tile_pixels;
    opt.max_unit_pixels = split.max_unit_pixels;
    opt.pass_spp = split.pass_spp;
    RenderResult r = render(devices, scene, opt);
    SCOPED_TRACE("tile " + std::to_string(split.tile_pixels) + ", unit " + std::to_string(split.max_unit_pixels) +
                 ", pass " + std::to_string(split.pass_spp));
    EXPECT_TRUE(same_bits(r.film, reference_film()));
    if (split.tile_pixels == 37) {  // AOVs too: their layers the one-device bits, the beauty's unchanged
      RenderOptions with_aovs = opt;
      with_aovs.aovs = (1u << PC_AOV_COUNT) - 1;
      Film one = render({devices.front()}, scene, with_aovs).film, all = render(devices, scene, with_aovs).film;
      EXPECT_TRUE(same_bits(all, one));
      EXPECT_TRUE(std::equal(reference_film().words.begin(), reference_film().words.end(), all.words.begin()));
    }
    EXPECT_EQ(r.determinism, "bitwise");
    EXPECT_EQ(r.film.spp, 12u);
    if (split.tile_pixels == 1) {  // a thousand units: every device gets some
      for (const DeviceReport& d : r.devices) EXPECT_GT(d.units, 0u) << d.name;
    }
    for (const DeviceReport& d : r.devices) EXPECT_EQ(d.arithmetic_class, 0u) << d.name;
  }
}

TEST(MultiDevice, ALaggingDeviceDoesNotChangeTheBits) {
  DeviceScene scene = load_device_scene(kCornell);
  scene.header.width = 96;
  scene.header.height = 80;
  std::vector<DeviceInfo> devices = all_devices();
  RenderOptions opt = base_options();
  opt.spp = 24;
  opt.power_of_two_horizons = true;  // horizons at 1, 2, 4, 8, 16: the lagging device holds them back
  Film one = render({devices.front()}, scene, opt).film;
  opt.tile_pixels = 32;
  opt.faults.resize(1);
  opt.faults[0].delay_seconds = 0.01;  // every unit of device 0 starts 10 ms late
  RenderResult r = render(devices, scene, opt);
  EXPECT_TRUE(same_bits(r.film, one));
  // How the work went depends on timing (on "pthread pthread" both devices share PoCL's one thread).
  std::printf("lagging device: %llu units; prompt device: %llu units, %llu copies run, %llu won; %llu compared\n",
              (unsigned long long)r.devices[0].units, (unsigned long long)r.devices[1].units,
              (unsigned long long)r.devices[1].duplicates_run, (unsigned long long)r.devices[1].duplicates_won,
              (unsigned long long)r.duplicate_checks);
}

TEST(MultiDevice, AFailingDeviceGivesItsUnitsBack) {
  std::vector<DeviceInfo> devices = all_devices();
  for (size_t failing : {0, 1}) {
    RenderOptions opt = base_options();
    // 144 one-sample units of at most 160 pixels: each device is given one at the start and another as soon
    // as it is done, so the failing device reaches its second unit whatever the timing (with 3 units it
    // once did not: the other device had taken the rest).
    opt.tile_pixels = 16;
    opt.max_unit_pixels = 160;
    opt.pass_spp = 1;
    opt.faults.resize(2);
    opt.faults[failing].fail_after_units = 1;
    RenderResult r = render(devices, small_cornell(), opt);
    EXPECT_TRUE(same_bits(r.film, reference_film())) << "device " << failing << " fails";
    EXPECT_EQ(r.devices[failing].failures, 1u);
    EXPECT_LE(r.devices[failing].units, 1u);  // committed: its copied units may have lost
    EXPECT_NE(r.devices[failing].note.find("test failure after 1 units"), std::string::npos) << r.devices[failing].note;
    ASSERT_FALSE(r.warnings.empty());
    EXPECT_NE(r.warnings.back().find("its units go to the other devices"), std::string::npos) << r.warnings.back();
  }
  // When every device fails, the render fails with each one's reason.
  RenderOptions opt = base_options();
  opt.tile_pixels = 16;
  opt.max_unit_pixels = 160;
  opt.pass_spp = 1;
  opt.faults.resize(2);
  opt.faults[0].fail_after_units = 0;
  opt.faults[1].fail_after_units = 1;
  try {
    render(devices, small_cornell(), opt);
    ADD_FAILURE() << "no failure";
  } catch (const RuntimeFailure& e) {
    EXPECT_NE(std::string(e.what()).find("every device failed"), std::string::npos) << e.what();
  }
}

// Light tracing, BDPT and photon merging splat anywhere: their light paths are split across the devices by
// index (the merging integrators' iterations too: each unit merges every camera path with its own light
// paths' vertices), each unit's splats come back as integers and are added exactly, so any split, a
// lagging device whose units are copied (only the winner's splats count) and a failing device (its
// unfinished unit's splats are dropped and the unit runs again elsewhere) all give the one-device film.
TEST(MultiDevice, SplatFilmsOnAllDevicesGiveTheOneDeviceBits) {
  DeviceScene scene = small_cornell();
  std::vector<DeviceInfo> devices = all_devices();
  for (const char* integrator : {"light", "bdpt", "vcm", "sppm"}) {
    // A merging unit traces all of its iteration's camera paths: units of 480 paths rather than 7.
    const bool merging = technique_named(integrator, "test").per_sample;
    SCOPED_TRACE(integrator);
    RenderOptions opt = base_options();
    opt.integrator = integrator;
    Film one = render({devices.front()}, scene, opt).film;
    ASSERT_EQ(one.words.size(), size_t(2 * PC_SPLAT_WORDS) * 48 * 40);
    auto same = [&](const RenderResult& r, const std::string& what) {
      EXPECT_EQ(r.film.words, one.words) << what;
      EXPECT_EQ(r.film.mean, one.mean) << what;
      EXPECT_EQ(r.splat_overflows, 0u) << what;
    };
    for (uint32_t tile : {1u, 37u, 0u}) {
      RenderOptions split = opt;
      split.tile_pixels = tile;
      split.max_unit_pixels = tile == 1 ? (merging ? 480 : 7) : 0;
      split.pass_spp = tile == 0 ? 0 : tile == 1 ? 1 : 5;
      RenderResult r = render(devices, scene, split);
      same(r, "tile " + std::to_string(tile));
      EXPECT_EQ(r.determinism, "bitwise");
      if (tile == 1) {
        for (const DeviceReport& d : r.devices) EXPECT_GT(d.units, 0u) << d.name;
      }
    }
    RenderOptions lagging = opt;
    lagging.tile_pixels = 64;
    lagging.power_of_two_horizons = true;
    lagging.faults.resize(1);
    lagging.faults[0].delay_seconds = 0.01;
    same(render(devices, scene, lagging), "a lagging device");
    RenderOptions failing = opt;  // 144 units of one sample: each device takes one at the start
    failing.tile_pixels = 16;
    failing.max_unit_pixels = 160;
    failing.pass_spp = 1;
    failing.faults.resize(2);
    failing.faults[1].fail_after_units = 1;
    RenderResult r = render(devices, scene, failing);
    same(r, "a failing device");
    EXPECT_EQ(r.devices[1].failures, 1u);
  }
}

// The gathering integrators run per-sample pixel units (each unit traces its iteration's light paths, then
// its pixels gather), mlt pixel units of chains whose states move between the devices in the film's ordered
// layer: any split over the devices, and a failing device, give the one-device bits.
TEST(MultiDevice, GatheringAndMetropolisOnAllDevicesGiveTheOneDeviceBits) {
  DeviceScene scene = small_cornell();
  std::vector<DeviceInfo> devices = all_devices();
  for (const char* integrator : {"instant_radiosity", "radiosity", "mlt"}) {
    SCOPED_TRACE(integrator);
    RenderOptions opt = base_options();
    opt.integrator = integrator;
    opt.light_paths = 24;
    opt.bootstrap = 256;
    Film one = render({devices.front()}, scene, opt).film;
    for (uint32_t tile : {1u, 37u, 0u}) {
      RenderOptions split = opt;
      split.tile_pixels = tile;
      split.max_unit_pixels = tile == 1 ? 7 : 0;
      split.pass_spp = tile == 0 ? 0 : tile == 1 ? 1 : 5;
      RenderResult r = render(devices, scene, split);
      EXPECT_EQ(r.film.words, one.words) << "tile " << tile;
      EXPECT_EQ(r.determinism, "bitwise");
      if (tile == 1) {
        for (const DeviceReport& d : r.devices) EXPECT_GT(d.units, 0u) << d.name;
      }
    }
    RenderOptions failing = opt;
    failing.tile_pixels = 16;
    failing.pass_spp = 1;
    failing.faults.resize(2);
    failing.faults[1].fail_after_units = 1;
    RenderResult r = render(devices, scene, failing);
    EXPECT_EQ(r.film.words, one.words) << "a failing device";
    EXPECT_EQ(r.devices[1].failures, 1u);
  }
}

TEST(MultiDevice, ACheckpointWrittenOnTwoDevicesResumesOnOne) {
  DeviceScene scene = small_cornell();
  RenderOptions opt = base_options();
  opt.spp = 40;
  opt.pass_spp = 3;
  opt.tile_pixels = 64;
  opt.checkpoint = temp_dir() + "/two-devices.ck";
  opt.checkpoint_every = 0;  // a checkpoint at every pass
  opt.checkpoint_key = render_key(scene, opt);
  volatile std::sig_atomic_t stop = 0;
  opt.interrupt = &stop;
  RenderCallbacks callbacks;
  callbacks.progress = [&](uint64_t done, uint64_t total, double) {
    if (done * 3 > total) stop = 1;  // a third of the way: as a SIGINT would
  };
  RenderResult part = render(all_devices(), scene, opt, callbacks);
  EXPECT_EQ(part.stop_reason, "interrupted");
  ASSERT_GT(part.film.spp, 0u);
  ASSERT_LT(part.film.spp, 40u);
  EXPECT_EQ(part.checkpoint_spp, part.film.spp);

  Film resumed = read_checkpoint(opt.checkpoint, scene, opt);
  EXPECT_EQ(resumed.spp, part.film.spp);
  RenderOptions again = base_options();
  again.spp = 40;
  again.pass_spp = 3;
  again.resume = &resumed;
  RenderResult rest = render({select_devices("all").back()}, scene, again);
  RenderOptions whole = base_options();
  whole.spp = 40;
  RenderResult uninterrupted = render({select_devices("all").front()}, scene, whole);
  EXPECT_EQ(rest.film.spp, 40u);
  EXPECT_TRUE(same_bits(rest.film, uninterrupted.film));
}

TEST(MultiDevice, ADeviceOfAnotherArithmeticClassIsLeftOutUnlessMixedIsAllowed) {
  std::vector<DeviceInfo> devices = all_devices();
  RenderOptions opt = base_options();
  opt.tile_pixels = 16;
  opt.faults.resize(2);
  opt.faults[1].perturb = true;  // one operation rounds the other way on device 1
  RenderResult r = render(devices, small_cornell(), opt);
  EXPECT_EQ(r.devices[1].arithmetic_class, 1u);
  EXPECT_FALSE(r.devices[1].used);
  EXPECT_EQ(r.devices[1].units, 0u);
  EXPECT_NE(r.devices[1].note.find("another arithmetic class"), std::string::npos) << r.devices[1].note;
  EXPECT_EQ(r.determinism, "bitwise");
  EXPECT_TRUE(same_bits(r.film, reference_film()));

  opt.allow_mixed_devices = true;
  opt.max_unit_pixels = 64;  // many units: both devices take some
  RenderResult mixed = render(devices, small_cornell(), opt);
  EXPECT_EQ(mixed.determinism, "mixed");
  EXPECT_TRUE(mixed.devices[1].used);
  EXPECT_GT(mixed.devices[1].units, 0u);
  EXPECT_FALSE(same_bits(mixed.film, reference_film()));  // the perturbed device's pixels differ
}

TEST(MultiDevice, CommandLineDeviceLists) {
  std::string dir = temp_dir() + "/cli", err, out;
  std::filesystem::create_directories(dir);
  std::string common = "render " + kCornell + " --spp 2 --quiet ";
  ASSERT_EQ(run_pathcl(common + "--device all -o " + dir + "/all.exr --stats " + dir + "/all.json", &err), 0) << err;
  ASSERT_EQ(run_pathcl(common + "--device 0 -o " + dir + "/one.exr", &err), 0) << err;
  EXPECT_EQ(read_exr(dir + "/all.exr").rgb, read_exr(dir + "/one.exr").rgb);
  EXPECT_EQ(read_exr(dir + "/all.exr").attributes["determinism"], "bitwise");
  std::string stats = read_text_file(dir + "/all.json");
  EXPECT_NE(stats.find("\"devices\""), std::string::npos);
  EXPECT_NE(stats.find("\"duplicates_won\""), std::string::npos);
  ASSERT_EQ(run_pathcl(common + "--device 1,0 -o " + dir + "/list.exr", &err), 0) << err;
  EXPECT_EQ(read_exr(dir + "/list.exr").rgb, read_exr(dir + "/one.exr").rgb);

  EXPECT_EQ(run_pathcl(common + "--device 0,0 -o " + dir + "/twice.exr", &err), 2);
  EXPECT_NE(err.find("selects device 0"), std::string::npos) << err;
  EXPECT_EQ(run_pathcl(common + "--device 0,,1 -o " + dir + "/empty.exr", &err), 2);
  EXPECT_NE(err.find("an empty selector"), std::string::npos) << err;
  EXPECT_EQ(run_pathcl(common + "--device 0,99 -o " + dir + "/none.exr", &err), 2);
  EXPECT_NE(err.find("no device with that index"), std::string::npos) << err;
  EXPECT_FALSE(std::filesystem::exists(dir + "/twice.exr") || std::filesystem::exists(dir + "/none.exr"));
}

// Listing the devices asks PoCL for one generic work-group function per kernel (runtime/device.cpp): without
// it a large render compiled its kernels again for wide launches, and every work-group size again. A value
// the user set holds.
TEST(MultiDevice, PoclGetsOneWorkGroupFunctionPerKernel) {
  const char* kVariable = "POCL_WORK_GROUP_SPECIALIZATION";
  unsetenv(kVariable);
  ASSERT_FALSE(list_devices().empty());
  ASSERT_NE(std::getenv(kVariable), nullptr);
  EXPECT_STREQ(std::getenv(kVariable), "0");
  setenv(kVariable, "1", 1);
  list_devices();
  EXPECT_STREQ(std::getenv(kVariable), "1");
  setenv(kVariable, "0", 1);
}
