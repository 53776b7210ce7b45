// The render schedule (runtime/render_schedule.h) driven by simulated devices: a discrete-event simulation
// with random speeds, launch latencies, jitter, lags and failures, no OpenCL and no clocks, so every run is
// exact and takes milliseconds. Checked: every pixel gets every sample exactly once and in order, no tile
// passes a horizon, copies are of the same range as their twins, a failed device's work is redone by the
// others, slow devices are dropped, adding a device never makes the render slower, and units settle at
// their target duration.
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <queue>
#include <cstdio>
#include <random>

#include <gtest/gtest.h>

#include "runtime/render_schedule.h"

namespace {

struct SimDevice {
  double rate = 1e6;         // samples per second once a launch runs
  double latency = 0;        // seconds per unit regardless of its size
  double jitter = 0;         // relative standard deviation of a unit's duration
  double fail_at = std::numeric_limits<double>::infinity();  // the unit running at this time fails
  double target = 0.1;
  bool mixed = false;
};

struct SimSettings {
  uint32_t pixels = 64 * 64, tile_pixels = 16, spp = 64, start_spp = 0;
  bool power_of_two_horizons = false;
  double close_every = 0;  // > 0: close the pass this often (checkpoints, time checks)
  uint32_t fixed_count = 0, max_unit_pixels = 0;
  uint64_t seed = 1;
};

struct SimResult {
  double seconds = 0;  // when the last tile reached spp
  bool finished = false;
  std::vector<ScheduleDeviceStats> stats;
  std::vector<double> unit_seconds;  // durations of committed units, in the order they finished
  std::vector<uint32_t> unit_device;  // and their devices
  uint32_t horizons = 0;
  uint64_t compares = 0;
  std::string failure;  // the first broken invariant
};

// Runs the schedule the way runtime/renderer.cpp does, with simulated devices.
SimResult simulate(const SimSettings& s, const std::vector<SimDevice>& devices) {
  std::vector<ScheduleDevice> sd(devices.size());
  for (size_t d = 0; d < devices.size(); ++d) {
    sd[d].target_seconds = devices[d].target;
    sd[d].mixed_class = devices[d].mixed;
    // As runtime/renderer.cpp does: the start-up probe's rate (256 samples, latency included) when there
    // are several devices.
    if (devices.size() > 1) sd[d].rate = 256 / (devices[d].latency + 256 / devices[d].rate);
  }
  RenderSchedule schedule(s.pixels, s.tile_pixels, s.start_spp, sd);
  if (s.fixed_count) schedule.fix_samples_per_unit(s.fixed_count);
  if (s.max_unit_pixels) schedule.limit_unit_pixels(s.max_unit_pixels);
  auto next_horizon = [&](uint32_t level) {
    uint32_t h = s.spp;
    if (s.power_of_two_horizons) {
      uint32_t p = 1;
      while (p <= level) p *= 2;
      h = std::min(h, p);
    }
    return h;
  };
  schedule.set_horizon(next_horizon(s.start_spp));

  std::mt19937_64 rng(s.seed);
  std::normal_distribution<double> normal;
  SimResult result;
  std::vector<uint32_t> level(schedule.tile_count(), s.start_spp);  // the samples committed per tile
  std::map<uint64_t, WorkUnit> units;
  struct Finish {
    double time;
    uint64_t unit;
    bool fails;
    bool operator>(const Finish& o) const { return time > o.time || (time == o.time && unit > o.unit); }
  };
  std::priority_queue<Finish, std::vector<Finish>, std::greater<Finish>> events;
  std::map<uint64_t, double> started;
  std::vector<bool> busy(devices.size(), false);
  double now = 0, last_close = 0;
  auto fail = [&](const std::string& what) {
    if (result.failure.empty()) result.failure = what + " at t=" + std::to_string(now);
  };
  for (int guard = 0; guard < 1000000; ++guard) {
    for (uint32_t d = 0; d < devices.size(); ++d) {
      if (busy[d]) continue;
      std::optional<WorkUnit> u = schedule.next_unit(d, now);
      if (!u) continue;
      if (u->sample_begin + u->sample_count > schedule.horizon()) fail("a unit passes the horizon");
      if (u->pixel_count == 0 || u->sample_count == 0) fail("an empty unit");
      if (u->pixel_begin != u->first_tile * s.tile_pixels) fail("a unit's pixels are not its tiles'");
      for (uint32_t t = u->first_tile; t < u->first_tile + u->tile_count; ++t)
        if (level[t] != u->sample_begin) fail("a unit does not start at its tiles' samples");
      if (u->duplicate) {
        const WorkUnit& o = units.at(u->original);
        if (o.pixel_begin != u->pixel_begin || o.pixel_count != u->pixel_count || o.sample_begin != u->sample_begin ||
            o.sample_count != u->sample_count)
          fail("a copy differs from its original");
        if (devices[d].mixed || devices[o.device].mixed) fail("a unit of a mixed-class device is copied");
      }
      double samples = double(u->pixel_count) * u->sample_count;
      double duration = devices[d].latency + samples / devices[d].rate;
      duration *= std::max(0.2, 1 + devices[d].jitter * normal(rng));
      bool fails = now + duration >= devices[d].fail_at;
      events.push({fails ? devices[d].fail_at : now + duration, u->id, fails});
      units[u->id] = *u;
      started[u->id] = now;
      busy[d] = true;
    }
    if (schedule.at_horizon()) {
      result.horizons++;
      uint32_t h = schedule.horizon();
      for (uint32_t t = 0; t < level.size(); ++t)
        if (level[t] != h) fail("at the horizon, a tile has another level");
      if (h >= s.spp) {
        result.finished = true;
        result.seconds = now;
        break;
      }
      schedule.set_horizon(next_horizon(h));
      continue;
    }
    if (events.empty()) break;  // nothing runs and nothing can start: every device failed
    Finish f = events.top();
    events.pop();
    now = f.time;
    const WorkUnit u = units.at(f.unit);
    busy[u.device] = false;
    if (f.fails) {
      schedule.fail(f.unit, "simulated failure");
    } else {
      double duration = now - started.at(f.unit);
      UnitFinish r = schedule.finish(f.unit, duration);
      if (r.outcome == UnitOutcome::committed) {
        for (uint32_t t = u.first_tile; t < u.first_tile + u.tile_count; ++t) {
          if (level[t] != u.sample_begin) fail("a committed unit does not continue its tiles' samples");
          level[t] = u.sample_begin + u.sample_count;
        }
        result.unit_seconds.push_back(duration);
        result.unit_device.push_back(u.device);
      } else if (r.outcome == UnitOutcome::compare) {
        const WorkUnit& twin = units.at(r.twin);
        if (twin.pixel_begin != u.pixel_begin || twin.sample_begin != u.sample_begin || twin.sample_count != u.sample_count)
          fail("a compared unit is not its twin's range");
        result.compares++;
      }
    }
    if (s.close_every > 0 && now - last_close >= s.close_every) {
      schedule.close_pass();
      last_close = now;
    }
  }
  for (uint32_t t = 0; t < level.size() && result.finished; ++t)
    if (level[t] != s.spp) fail("a tile did not get every sample");
  result.stats = schedule.device_stats();
  return result;
}

}  // namespace

TEST(RenderSchedule, OneDeviceGivesEveryPixelEverySampleInOrder) {
  for (uint32_t tile : {1u, 7u, 16u, 4096u}) {
    SimSettings s;
    s.tile_pixels = tile;
    SimResult r = simulate(s, {SimDevice{}});
    EXPECT_TRUE(r.finished) << tile;
    EXPECT_EQ(r.failure, "") << tile;
    EXPECT_EQ(r.stats[0].samples, uint64_t(s.pixels) * s.spp);
  }
}

TEST(RenderSchedule, RandomDevicesDelaysAndFailuresNeverBreakTheOrder) {
  std::mt19937_64 rng(2026);
  std::uniform_real_distribution<double> uniform(0, 1);
  int finished = 0;
  for (int trial = 0; trial < 300; ++trial) {
    SimSettings s;
    s.seed = trial;
    s.pixels = 1 + uint32_t(uniform(rng) * 5000);
    s.tile_pixels = 1 + uint32_t(uniform(rng) * 300);
    s.spp = 1 + uint32_t(uniform(rng) * 100);
    s.start_spp = uniform(rng) < 0.2 ? uint32_t(uniform(rng) * s.spp) : 0;
    s.power_of_two_horizons = uniform(rng) < 0.5;
    s.close_every = uniform(rng) < 0.3 ? uniform(rng) * 0.5 : 0;
    s.fixed_count = uniform(rng) < 0.3 ? 1 + uint32_t(uniform(rng) * 6) : 0;
    s.max_unit_pixels = uniform(rng) < 0.3 ? 1 + uint32_t(uniform(rng) * 2000) : 0;
    std::vector<SimDevice> devices(1 + size_t(uniform(rng) * 4));
    for (SimDevice& d : devices) {
      d.rate = std::pow(10.0, 4 + 3 * uniform(rng));
      d.latency = uniform(rng) < 0.5 ? uniform(rng) * 0.01 : 0;
      d.jitter = uniform(rng) * 0.5;
      d.target = uniform(rng) < 0.5 ? 0.075 : 0.25;
      if (uniform(rng) < 0.25) d.fail_at = uniform(rng) * 2;
    }
    SimResult r = simulate(s, devices);
    ASSERT_EQ(r.failure, "") << "trial " << trial;
    bool any_survivor = std::any_of(devices.begin(), devices.end(), [](const SimDevice& d) { return std::isinf(d.fail_at); });
    // Every device may fail; with one that does not, the render always finishes.
    if (any_survivor) { ASSERT_TRUE(r.finished) << "trial " << trial; }
    finished += r.finished;
    uint64_t committed = 0;
    for (const ScheduleDeviceStats& st : r.stats) committed += st.samples;
    if (r.finished) { EXPECT_EQ(committed, uint64_t(s.pixels) * (s.spp - s.start_spp)) << "trial " << trial; }
  }
  EXPECT_GT(finished, 200);
}

TEST(RenderSchedule, AFailedDevicesUnitsAreRedoneByTheOthers) {
  SimSettings s;
  std::vector<SimDevice> devices(2);
  s.spp = 1024;              // 4096 pixels x 1024 samples at 2e6 samples/s: about 2 s
  devices[1].fail_at = 0.5;  // mid-render
  SimResult r = simulate(s, devices);
  EXPECT_EQ(r.failure, "");
  EXPECT_TRUE(r.finished);
  EXPECT_EQ(r.stats[1].failures, 1u);
  EXPECT_FALSE(r.stats[1].active);
  EXPECT_GT(r.stats[1].samples, 0u);  // it helped before it failed
  EXPECT_EQ(r.stats[0].samples + r.stats[1].samples, uint64_t(s.pixels) * s.spp);
}

TEST(RenderSchedule, AddingADeviceNeverMakesTheRenderSlower) {
  SimSettings s;
  s.pixels = 256 * 256;
  s.tile_pixels = 256;
  s.spp = 1024;  // about 0.7 s on the fast device alone
  s.power_of_two_horizons = true;
  SimDevice fast;  // a GPU
  fast.rate = 1e8;
  fast.latency = 0.0002;
  fast.target = 0.075;
  double alone = simulate(s, {fast}).seconds;
  for (uint64_t seed : {1, 2, 3})
    for (double share : {1.0, 0.5, 0.1, 0.03, 0.01, 0.001}) {
      SimDevice slow;
      slow.rate = fast.rate * share;
      slow.jitter = 0.2;
      s.seed = seed;
      SimResult both = simulate(s, {slow, fast});  // the slow one listed first
      EXPECT_EQ(both.failure, "");
      EXPECT_LE(both.seconds, alone * 1.03) << "a device at " << share << " of the fast one's speed, seed " << seed;
      // And it helps: within 20 % of the ideal time, the fast one's alone over the combined speed.
      double efficiency = alone / (1 + share) / both.seconds;
      if (share >= 0.1) { EXPECT_GE(efficiency, 1 / 1.2) << share << ", seed " << seed; }
      if (share <= 0.01) { EXPECT_TRUE(both.stats[0].dropped) << share << ", seed " << seed; }
      std::printf("a device at %g of the fast one's speed, seed %d: %.4f s, alone %.4f s, efficiency %.3f\n", share,
                  int(seed), both.seconds, alone, efficiency);
    }
}

TEST(RenderSchedule, TwoEqualDevicesShareTheWork) {
  SimSettings s;
  s.pixels = 512 * 512;
  s.tile_pixels = 1024;
  s.spp = 64;
  SimDevice d;
  d.rate = 2e6;
  d.jitter = 0.1;
  d.target = 0.25;
  double alone = simulate(s, {d}).seconds;
  SimResult two = simulate(s, {d, d});
  EXPECT_EQ(two.failure, "");
  double efficiency = alone / (2 * two.seconds);
  EXPECT_GT(efficiency, 0.9);
  EXPECT_NEAR(double(two.stats[0].samples) / (two.stats[0].samples + two.stats[1].samples), 0.5, 0.1);
}

TEST(RenderSchedule, AnIdleDeviceCopiesASlowDevicesUnitAndWins) {
  SimSettings s;
  s.pixels = 128 * 128;
  s.tile_pixels = 64;
  s.spp = 32;
  s.power_of_two_horizons = true;
  SimDevice slow, fast;
  slow.rate = 2e5;
  slow.jitter = 0.5;  // its units take up to twice what its rate promises
  fast.rate = 2e6;
  SimResult r = simulate(s, {slow, fast});
  EXPECT_EQ(r.failure, "");
  EXPECT_GT(r.stats[1].duplicates_run, 0u);
  EXPECT_GT(r.stats[1].duplicates_won, 0u);
  EXPECT_GT(r.compares, 0u);  // the slow originals finished later and were compared
}

TEST(RenderSchedule, MixedClassDevicesAreNeverCopied) {
  SimSettings s;
  s.power_of_two_horizons = true;
  SimDevice slow, fast;
  slow.rate = 2e5;
  slow.jitter = 0.5;
  slow.mixed = true;
  fast.rate = 2e6;
  SimResult r = simulate(s, {slow, fast});
  EXPECT_EQ(r.failure, "");
  EXPECT_TRUE(r.finished);
  EXPECT_EQ(r.stats[1].duplicates_run + r.stats[0].duplicates_run, 0u);
}

TEST(RenderSchedule, UnitsSettleAtTheirTargetDurationFromAnySpeed) {
  // From a device that needs many samples per pixel per unit to one that must split the film.
  for (double rate : {1e5, 1e6, 1e7, 1e8, 1e9}) {
    SimSettings s;
    s.pixels = 1024 * 1024;
    s.tile_pixels = 4096;
    s.spp = uint32_t(std::clamp(rate * 2 / s.pixels, 1.0, 4096.0));  // about 2 s of rendering
    SimDevice gpu;
    gpu.rate = rate;
    gpu.latency = 0.0005;
    gpu.target = 0.075;
    SimResult r = simulate(s, {gpu});
    ASSERT_TRUE(r.finished);
    std::vector<double> later(r.unit_seconds.begin() + r.unit_seconds.size() / 2, r.unit_seconds.end());
    std::sort(later.begin(), later.end());
    double median = later[later.size() / 2];
    // Counts are powers of two up to 256 per unit: within a factor of two of the target, unless the whole
    // film at 256 samples is faster still.
    if (rate * 0.075 / s.pixels < 256) {
      EXPECT_GE(median, 0.075 / 2.2) << rate;
      EXPECT_LE(median, 0.075 * 1.6) << rate;
    }
  }
}
