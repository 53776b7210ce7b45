#include "runtime/render_schedule.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace {

constexpr uint32_t kNotHeld = std::numeric_limits<uint32_t>::max();
constexpr uint32_t kMaxSamplesPerUnit = 256;
constexpr double kDropShare = 0.03;   // a device under this share of the combined rate is dropped
constexpr uint64_t kUnitsBeforeDrop = 2;  // finished units before its rate counts

uint32_t floor_power_of_two(double x) {
  uint32_t p = 1;
  while (p < kMaxSamplesPerUnit && 2.0 * p <= x) p *= 2;
  return p;
}

}  // namespace

RenderSchedule::RenderSchedule(uint32_t pixels, uint32_t tile_pixels, uint32_t start_spp,
                               std::vector<ScheduleDevice> devices)
    : pixels_(std::max(pixels, 1u)),
      tile_pixels_(std::clamp(tile_pixels, 1u, std::max(pixels, 1u))),
      horizon_(start_spp),
      devices_(std::move(devices)),
      stats_(devices_.size()) {
  uint32_t tiles = (pixels_ + tile_pixels_ - 1) / tile_pixels_;
  level_.assign(tiles, start_spp);
  owner_.assign(tiles, 0);
  // A fresh render starts from zeroed accumulators, which every device clears itself; a resumed one
  // must send the checkpoint's.
  held_.assign(devices_.size(), std::vector<uint32_t>(tiles, start_spp == 0 ? 0u : kNotHeld));
}

uint32_t RenderSchedule::default_tile_pixels(uint32_t pixels) { return std::max(1u, (pixels + 255) / 256); }

uint32_t RenderSchedule::tile_size(uint32_t t) const {
  return std::min(tile_pixels_, pixels_ - tile_begin(t));
}

void RenderSchedule::set_horizon(uint32_t spp) {
  uint32_t highest = *std::max_element(level_.begin(), level_.end());
  if (spp < highest) throw std::logic_error("RenderSchedule: horizon below a tile's level");
  horizon_ = spp;
}

void RenderSchedule::close_pass() {
  uint32_t h = *std::max_element(level_.begin(), level_.end());
  for (const auto& [id, r] : running_)
    if (!r.abandoned) h = std::max(h, r.unit.sample_begin + r.unit.sample_count);
  horizon_ = std::min(horizon_, h);
}

bool RenderSchedule::at_horizon() const {
  return std::all_of(level_.begin(), level_.end(), [&](uint32_t l) { return l >= horizon_; });
}

uint64_t RenderSchedule::samples_done() const {
  uint64_t samples = 0;
  for (uint32_t t = 0; t < level_.size(); ++t) samples += uint64_t(level_[t]) * tile_size(t);
  return samples;
}

uint32_t RenderSchedule::lowest_level() const { return *std::min_element(level_.begin(), level_.end()); }

bool RenderSchedule::any_active_device() const {
  return std::any_of(stats_.begin(), stats_.end(), [](const ScheduleDeviceStats& s) { return s.active; });
}

bool RenderSchedule::busy(uint32_t device) const {
  for (const auto& [id, r] : running_)
    if (r.unit.device == device) return true;
  return false;
}

const WorkUnit* RenderSchedule::running(uint64_t unit) const {
  auto it = running_.find(unit);
  return it == running_.end() ? nullptr : &it->second.unit;
}

void SpeedModel::add(double samples, double seconds) {
  const double keep = 0.75;  // older units count less: speeds change (clocks, other load)
  n_ = keep * n_ + 1;
  x_ = keep * x_ + samples;
  y_ = keep * y_ + seconds;
  xx_ = keep * xx_ + samples * samples;
  xy_ = keep * xy_ + samples * seconds;
  double det = n_ * xx_ - x_ * x_;
  double slope = det > 1e-6 * n_ * xx_ ? (n_ * xy_ - x_ * y_) / det : 0;
  double intercept = slope > 0 ? (y_ - slope * x_) / n_ : -1;
  if (slope > 0 && intercept >= 0) {
    latency = intercept;
    seconds_per_sample = slope;
  } else {  // sizes too alike to tell latency from throughput, or noise: no latency
    latency = 0;
    seconds_per_sample = xx_ > 0 ? xy_ / xx_ : 0;
  }
}

double SpeedModel::samples_in(double seconds) const {
  return known() ? std::max(seconds - latency, 0.5 * seconds) / seconds_per_sample : 0;
}

double RenderSchedule::throughput(uint32_t device) const {
  const SpeedModel& speed = stats_[device].speed;
  // Two units of different sizes tell latency from throughput. Until then a device counts as fast as
  // the fastest measured one, or its probe: a first unit small enough to be all latency would otherwise
  // make a fast device look slow, and it would never get the larger unit that shows its speed. Its own
  // model (slow until corrected) still limits how large its units are.
  if (speed.known() && stats_[device].finished >= 2) return speed.throughput();
  double best = std::max(speed.throughput(), devices_[device].rate);
  for (size_t d = 0; d < devices_.size(); ++d)
    if (stats_[d].active && d != device) best = std::max(best, stats_[d].speed.throughput());
  return best;
}

double RenderSchedule::active_throughput() const {
  double sum = 0;
  for (uint32_t d = 0; d < devices_.size(); ++d)
    if (stats_[d].active) sum += throughput(d);
  return sum;
}

uint32_t RenderSchedule::count_from(uint32_t level) {
  auto it = next_level_.find(level);
  if (it != next_level_.end()) return it->second - level;
  uint32_t count = fixed_count_;
  if (count == 0) {
    // The combined throughput fills the film in about the fastest device's target time, or in the longest
    // target of a device that asks for few, large units (another rank's: each unit carries its pixels'
    // accumulators over the network, so a unit should add many samples to each pixel it carries).
    double fastest = 0, target = 0.1, few_units_target = 0;
    for (uint32_t d = 0; d < devices_.size(); ++d) {
      if (!stats_[d].active) continue;
      if (throughput(d) > fastest) {
        fastest = throughput(d);
        target = devices_[d].target_seconds;
      }
      if (devices_[d].few_units) few_units_target = std::max(few_units_target, devices_[d].target_seconds);
    }
    count = floor_power_of_two(active_throughput() * std::max(target, few_units_target) / pixels_);
  }
  uint32_t next = std::min(level + count, horizon_);
  next_level_[level] = next;
  return next - level;
}

uint32_t RenderSchedule::unit_pixel_limit(uint32_t device, uint32_t count, double now) const {
  const SpeedModel& speed = stats_[device].speed;
  // An unmeasured device starts small: its first unit measures it.
  double limit = speed.known() ? speed.samples_in(devices_[device].target_seconds) / count : 4.0 * tile_pixels_;
  if (max_unit_pixels_ > 0) limit = std::min(limit, double(max_unit_pixels_));
  // The work left before the horizon, split so that the devices taking part would finish their parts at
  // one time T: each starts when its running unit is expected to end (now, for this one, and for one
  // not measured yet), and start_d + latency_d + w_d / throughput_d = T, with the w_d adding up to what
  // is left. A device whose part would be under its smallest worthwhile unit (a tile, or four times its
  // latency of work) does not take part: it would hold the horizon back. The fastest always does.
  double left = 0;
  for (uint32_t t = 0; t < level_.size(); ++t)
    if (owner_[t] == 0 && level_[t] < horizon_) left += double(horizon_ - level_[t]) * tile_size(t);
  std::vector<uint32_t> part;
  std::vector<double> start(devices_.size(), now);
  uint32_t fastest = device;
  for (uint32_t d = 0; d < devices_.size(); ++d)
    if (stats_[d].active && throughput(d) > 0) {
      part.push_back(d);
      if (throughput(d) > throughput(fastest)) fastest = d;
    }
  if (part.size() < 2) return uint32_t(std::clamp(limit, 1.0, double(pixels_)));
  for (const auto& [id, r] : running_) {
    const SpeedModel& its = stats_[r.unit.device].speed;
    if (!r.abandoned && r.unit.device != device && its.known())
      start[r.unit.device] = std::max(now, r.start + its.seconds(double(r.unit.pixel_count) * r.unit.sample_count));
  }
  auto smallest = [&](uint32_t d) {  // pixels: a tile, or four times the device's latency of work
    return std::max(double(tile_pixels_), 4 * stats_[d].speed.latency * throughput(d) / count);
  };
  for (;;) {
    double rate_sum = 0, begun = 0;
    for (uint32_t d : part) {
      rate_sum += throughput(d);
      begun += (start[d] + stats_[d].speed.latency) * throughput(d);
    }
    double finish = (left + begun) / rate_sum;
    auto share = [&](uint32_t d) {  // pixels
      return (finish - start[d] - stats_[d].speed.latency) * throughput(d) / count;
    };
    auto out = std::find_if(part.begin(), part.end(), [&](uint32_t d) { return d != fastest && share(d) < smallest(d); });
    if (out == part.end()) {
      // Alone, it takes what it can. Else half its part, so that what is left is split again with what
      // the devices' next units show (speeds vary), down to its smallest worthwhile unit; in whole tiles,
      // so that rounding never leaves a sliver.
      if (part.size() > 1)
        limit = std::min(limit, std::ceil(std::max(share(device) / 2, smallest(device)) / tile_pixels_) * tile_pixels_);
      break;
    }
    if (*out == device) return 0;
    part.erase(out);
  }
  return uint32_t(std::clamp(limit, 1.0, double(pixels_)));
}

std::optional<WorkUnit> RenderSchedule::next_unit(uint32_t device, double now) {
  if (!stats_[device].active || busy(device)) return std::nullopt;
  // The least-advanced free tiles below the horizon.
  uint32_t lowest = std::numeric_limits<uint32_t>::max();
  for (uint32_t t = 0; t < level_.size(); ++t)
    if (owner_[t] == 0 && level_[t] < horizon_) lowest = std::min(lowest, level_[t]);
  if (lowest == std::numeric_limits<uint32_t>::max()) return copy_of_oldest(device, now);
  uint32_t count = count_from(lowest);
  uint32_t limit = unit_pixel_limit(device, count, now);
  if (limit == 0) {
    // Too slow for even a tile of what is left. Measured and under 3 % of the combined throughput, it
    // leaves the render; else it waits for the next horizon.
    if (stats_[device].speed.known() && throughput(device) < kDropShare * active_throughput()) {
      stats_[device].dropped = true;
      remove_device(device, "dropped: under 3 % of the combined samples per second");
    }
    return std::nullopt;
  }
  // Runs of free tiles at that level: the first one this device holds a tile of (no upload), else the
  // longest. The fastest device takes from a run's start, the others from its end, so that the runs
  // stay long and the devices keep to their own parts of the film from level to level.
  uint32_t run_begin = 0, run_end = 0;
  bool run_held = false;
  for (uint32_t t = 0; t < level_.size();) {
    if (owner_[t] != 0 || level_[t] != lowest) {
      ++t;
      continue;
    }
    uint32_t end = t;
    bool held = false;
    while (end < level_.size() && owner_[end] == 0 && level_[end] == lowest) held |= held_[device][end++] == lowest;
    if ((held && !run_held) || (held == run_held && end - t > run_end - run_begin)) {
      run_begin = t;
      run_end = end;
      run_held = held;
    }
    t = end;
  }
  bool fastest = true;
  for (uint32_t d = 0; d < devices_.size(); ++d)
    if (d != device && stats_[d].active && throughput(d) > throughput(device)) fastest = false;
  uint32_t first = run_begin, last = run_begin;  // tiles [first, last)
  uint32_t pixels = 0;
  if (fastest) {
    while (last < run_end && (last == first || pixels + tile_size(last) <= limit)) pixels += tile_size(last++);
  } else {
    first = last = run_end;
    while (first > run_begin && (first == last || pixels + tile_size(first - 1) <= limit)) pixels += tile_size(--first);
  }

  WorkUnit u;
  u.id = next_id_++;
  u.device = device;
  u.first_tile = first;
  u.tile_count = last - first;
  u.pixel_begin = tile_begin(first);
  u.pixel_count = pixels;
  u.sample_begin = lowest;
  u.sample_count = count;
  for (uint32_t t = first; t < last; ++t) {
    owner_[t] = u.id;
    u.upload |= held_[device][t] != lowest;
  }
  running_[u.id] = Running{u, now};
  return u;
}

std::optional<WorkUnit> RenderSchedule::copy_of_oldest(uint32_t device, double now) {
  const SpeedModel& mine = stats_[device].speed;
  if (devices_[device].mixed_class || !mine.known()) return std::nullopt;
  Running* oldest = nullptr;
  for (auto& [id, r] : running_) {
    const WorkUnit& u = r.unit;
    if (r.twin != 0 || r.abandoned || u.device == device || devices_[u.device].mixed_class) continue;
    double samples = double(u.pixel_count) * u.sample_count;
    const SpeedModel& its = stats_[u.device].speed;
    // A unit past its expected end may still take a while: count a quarter of its expected time from now.
    double its_finish = its.known() ? std::max(r.start + its.seconds(samples), now + 0.25 * its.seconds(samples))
                                    : std::numeric_limits<double>::infinity();
    if (now + mine.seconds(samples) >= its_finish) continue;  // it would not win
    if (!oldest || r.start < oldest->start) oldest = &r;
  }
  if (!oldest) return std::nullopt;
  WorkUnit u = oldest->unit;
  u.original = u.id;
  u.id = next_id_++;
  u.device = device;
  u.duplicate = true;
  u.upload = false;
  for (uint32_t t = u.first_tile; t < u.first_tile + u.tile_count; ++t) u.upload |= held_[device][t] != u.sample_begin;
  oldest->twin = u.id;
  Running copy{u, now};
  copy.twin = u.original;
  running_[u.id] = copy;
  stats_[device].duplicates_run++;
  return u;
}

UnitFinish RenderSchedule::finish(uint64_t unit, double seconds) {
  auto it = running_.find(unit);
  if (it == running_.end()) throw std::logic_error("RenderSchedule: finish of a unit that is not running");
  Running r = it->second;
  running_.erase(it);
  const WorkUnit& u = r.unit;
  ScheduleDeviceStats& s = stats_[u.device];
  s.busy_seconds += seconds;
  s.finished++;
  double samples = double(u.pixel_count) * u.sample_count;
  if (seconds > 0) s.speed.add(samples, seconds);
  UnitFinish result{UnitOutcome::discard, r.twin};
  uint32_t end = u.sample_begin + u.sample_count;
  if (r.abandoned) {
    result.twin = r.twin_committed ? r.twin : 0;  // the twin's kept result is no longer needed
  } else if (r.twin_committed) {
    result.outcome = UnitOutcome::compare;
    for (uint32_t t = u.first_tile; t < u.first_tile + u.tile_count; ++t) held_[u.device][t] = end;
  } else {
    result.outcome = UnitOutcome::committed;
    for (uint32_t t = u.first_tile; t < u.first_tile + u.tile_count; ++t) {
      level_[t] = end;
      owner_[t] = 0;
      held_[u.device][t] = end;
    }
    s.units++;
    s.samples += uint64_t(samples);
    if (u.duplicate) s.duplicates_won++;
    auto twin = running_.find(r.twin);
    if (twin != running_.end()) twin->second.twin_committed = true;
    else result.twin = 0;
  }
  maybe_drop_slow_devices();
  return result;
}

void RenderSchedule::release(const Running& r) {
  // The twin, if one runs and has not lost already, takes the tiles over; else they go back to the pool.
  auto twin = running_.find(r.twin);
  bool twin_takes_over = twin != running_.end() && !r.twin_committed;
  for (uint32_t t = r.unit.first_tile; t < r.unit.first_tile + r.unit.tile_count; ++t)
    if (owner_[t] == r.unit.id || owner_[t] == r.twin) owner_[t] = twin_takes_over ? r.twin : 0;
  if (twin != running_.end()) twin->second.twin = 0;
}

void RenderSchedule::fail(uint64_t unit, const std::string& why) {
  auto it = running_.find(unit);
  if (it == running_.end()) throw std::logic_error("RenderSchedule: failure of a unit that is not running");
  Running r = it->second;
  running_.erase(it);
  if (!r.abandoned && !r.twin_committed) release(r);
  stats_[r.unit.device].failures++;
  remove_device(r.unit.device, why);
}

void RenderSchedule::remove_device(uint32_t device, const std::string& why) {
  ScheduleDeviceStats& s = stats_[device];
  if (s.active) s.left_because = why;
  s.active = false;
  // With every device gone, the slow ones dropped earlier are better than none.
  if (!any_active_device())
    for (ScheduleDeviceStats& other : stats_)
      if (other.dropped && other.failures == 0) {
        other.active = true;
        other.dropped = false;
        other.left_because.clear();
      }
  std::fill(held_[device].begin(), held_[device].end(), kNotHeld);
  for (auto& [id, r] : running_)
    if (r.unit.device == device && !r.abandoned) {
      if (!r.twin_committed) {
        release(r);
        r.twin = 0;
      }
      r.abandoned = true;
    }
}

void RenderSchedule::maybe_drop_slow_devices() {
  size_t active = std::count_if(stats_.begin(), stats_.end(), [](const ScheduleDeviceStats& s) { return s.active; });
  // Only once every active device is measured: an unmeasured device's speed says nothing yet.
  for (const ScheduleDeviceStats& s : stats_)
    if (s.active && s.finished < kUnitsBeforeDrop) return;
  for (uint32_t d = 0; d < devices_.size() && active > 1; ++d) {
    if (!stats_[d].active || throughput(d) >= kDropShare * active_throughput()) continue;
    stats_[d].dropped = true;
    remove_device(d, "dropped: under 3 % of the combined samples per second");
    --active;
  }
}
