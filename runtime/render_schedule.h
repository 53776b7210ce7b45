// Which pixels get which samples on which device: the schedule of a render over one or several devices.
// Plain C++ without OpenCL, threads or clocks (time is an argument), so tests/render_schedule_test.cpp
// drives it with simulated devices; runtime/renderer.cpp drives it with real ones.
//
// The film is cut into tiles of consecutive pixels. Each tile has a level: the number of samples its
// pixels hold. A work unit is a run of consecutive tiles at one level L and the samples [L, L + count): the
// device adds them to the pixels' accumulators, which the unit carries (runtime/device_worker.h), and the
// result is copied over those tiles of the film. The samples of a pixel are therefore added strictly in
// order, on whichever devices, and copying disjoint ranges involves no floating-point reduction: the film
// is the same bits for any split, any device set and any timing.
//
// All tiles step through one sequence of levels (0, c0, c0 + c1, ...): the first unit to leave a level
// fixes the count of every unit leaving it, so tiles at one level form long runs and units stay large.
// Units never go past the horizon, a level that every tile reaches before any goes further: the render
// loop sets it at the sample counts where it must see the whole film at one spp (the end, powers of two
// for convergence rows and error targets, checkpoints, time and interrupt checks).
//
// Sizing and balance: each device has a target unit duration and a speed model fitted to its finished
// units, seconds = latency + samples / throughput (so that small, latency-bound units do not make a fast
// device look slow). A new level's count c is chosen so that the devices' combined throughput fills the
// whole film in about the fastest one's target time (at least 1, at most 256 samples); a unit takes at most
// the pixels its device renders in its target time at that count, and at most its part of the work left
// before the horizon, split so that all devices would finish it at once: units shrink as the horizon
// nears, and a device too slow for even one tile of what is left waits. An idle device with nothing left
// below the horizon runs a copy of the oldest unit of a device it would beat; the first result wins and
// the other is compared with it bit for bit (a free identity check). A device with under 3 % of the
// combined throughput is dropped once it is measured, so adding a slow device never slows a render.
#pragma once
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

struct ScheduleDevice {
  double target_seconds = 0.1;  // unit duration to aim for (GPU: 75 ms, within its watchdog)
  double rate = 0;              // samples per second before any unit is measured (the probe), 0: unknown
  bool mixed_class = false;     // computes other bits than device 0 (--allow-mixed-devices): no copies
  // Each unit costs it a fixed latency and its pixels' accumulators moved both ways (another MPI rank's
  // device): levels are then counted so that the combined throughput fills the film in its target time too.
  bool few_units = false;
};

// seconds = latency + samples * seconds_per_sample, least squares over a device's recent units.
struct SpeedModel {
  double latency = 0, seconds_per_sample = 0;  // 0: not measured
  void add(double samples, double seconds);
  bool known() const { return seconds_per_sample > 0; }
  double throughput() const { return known() ? 1 / seconds_per_sample : 0; }
  double seconds(double samples) const { return latency + samples * seconds_per_sample; }
  double samples_in(double seconds) const;  // how many fit in `seconds`, at least half of it after latency

 private:
  double n_ = 0, x_ = 0, y_ = 0, xx_ = 0, xy_ = 0;  // decayed sums of samples (x) and seconds (y)
};

struct WorkUnit {
  uint64_t id = 0;
  uint32_t device = 0;
  uint32_t first_tile = 0, tile_count = 0;
  uint32_t pixel_begin = 0, pixel_count = 0;
  uint32_t sample_begin = 0, sample_count = 0;
  bool upload = false;     // the device's copy of these pixels is not at sample_begin: send the film's
  bool duplicate = false;  // a copy of another device's unit
  uint64_t original = 0;   // for a duplicate: the unit it copies
};

// What became of a finished unit.
enum class UnitOutcome {
  committed,  // first result: copy it into the film
  compare,    // its twin finished first and was committed: compare the two results bit for bit
  discard,    // its device was dropped or failed meanwhile: nothing to do with it
};
struct UnitFinish {
  UnitOutcome outcome = UnitOutcome::discard;
  uint64_t twin = 0;  // committed: the twin still running (keep this result to compare with); compare: the twin
};

struct ScheduleDeviceStats {
  uint64_t units = 0, samples = 0;       // committed units and the samples in them
  uint64_t finished = 0;                 // units finished, committed or not
  uint64_t duplicates_run = 0, duplicates_won = 0;
  uint64_t failures = 0;
  double busy_seconds = 0;               // time of its finished units, won or lost
  bool active = true, dropped = false;
  SpeedModel speed;
  std::string left_because;              // why it stopped taking units ("failed: ...", "under 3 % ...")
};

class RenderSchedule {
 public:
  // pixels of the film in tiles of tile_pixels (the last may be shorter); every tile starts at level
  // start_spp (a resumed render); the horizon starts there too.
  RenderSchedule(uint32_t pixels, uint32_t tile_pixels, uint32_t start_spp, std::vector<ScheduleDevice> devices);

  // A tile size for a film rendered on some devices: about 256 tiles, at least 1 pixel each.
  static uint32_t default_tile_pixels(uint32_t pixels);

  // Fixed limits instead of the adaptive ones (tests, --pass-spp): samples per level step, pixels per unit.
  void fix_samples_per_unit(uint32_t count) { fixed_count_ = count; }
  void limit_unit_pixels(uint32_t pixels) { max_unit_pixels_ = pixels; }

  void set_horizon(uint32_t spp);  // at least every tile's level
  uint32_t horizon() const { return horizon_; }
  // Lowers the horizon to the highest level a tile holds or a running unit will give it: the units
  // running now finish the current pass, and then every pixel has that many samples.
  void close_pass();
  // Every tile has reached the horizon (copies may still be running).
  bool at_horizon() const;
  uint32_t lowest_level() const;

  // Work for an idle device at time `now`, or nothing (it waits for the next event).
  std::optional<WorkUnit> next_unit(uint32_t device, double now);
  // A unit finished after `seconds` of its device's time (launch, transfers). Updates the device's rate.
  UnitFinish finish(uint64_t unit, double seconds);
  // A unit failed: its device leaves the render, its tiles go back to the pool (or to its copy).
  void fail(uint64_t unit, const std::string& why);
  // A device leaves without a running unit to blame (its set-up failed).
  void remove_device(uint32_t device, const std::string& why);

  bool any_active_device() const;
  bool busy(uint32_t device) const;         // a unit of this device is running
  bool idle() const { return running_.empty(); }
  const std::vector<ScheduleDeviceStats>& device_stats() const { return stats_; }
  const std::vector<ScheduleDevice>& devices() const { return devices_; }
  uint32_t tile_count() const { return uint32_t(level_.size()); }
  uint64_t samples_done() const;  // committed samples over the whole film
  const WorkUnit* running(uint64_t unit) const;  // nullptr once finished

 private:
  struct Running {
    WorkUnit unit;
    double start = 0;
    uint64_t twin = 0;            // the copy of this unit, or the original of this copy; 0 for none
    bool twin_committed = false;  // the twin finished first: this one only gets compared
    bool abandoned = false;       // its device left: the result is not wanted
  };
  uint32_t tile_begin(uint32_t t) const { return t * tile_pixels_; }
  uint32_t tile_size(uint32_t t) const;
  uint32_t count_from(uint32_t level);   // the level step's count, chosen once
  double throughput(uint32_t device) const;   // measured, else the initial estimate, else the best measured
  double active_throughput() const;
  // Pixels a unit of `count` samples on `device` may take; 0: the device should wait (too slow for what
  // is left before the horizon).
  uint32_t unit_pixel_limit(uint32_t device, uint32_t count, double now) const;
  std::optional<WorkUnit> copy_of_oldest(uint32_t device, double now);
  void release(const Running& r);
  void maybe_drop_slow_devices();

  uint32_t pixels_, tile_pixels_;
  std::vector<uint32_t> level_;              // per tile
  std::vector<uint64_t> owner_;              // per tile: the running unit on it, 0 when free
  std::vector<std::vector<uint32_t>> held_;  // [device][tile]: level of the device's copy, kNotHeld
  std::map<uint32_t, uint32_t> next_level_;  // level -> the level units leaving it reach
  uint32_t horizon_;
  std::vector<ScheduleDevice> devices_;
  std::vector<ScheduleDeviceStats> stats_;
  std::map<uint64_t, Running> running_;
  uint64_t next_id_ = 1;
  uint32_t fixed_count_ = 0, max_unit_pixels_ = 0;
};
