#include "runtime/renderer.h"

#include <algorithm>
#include <cmath>
#include <chrono>
#include <condition_variable>
#include <cstring>
#include <deque>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <thread>

#include "runtime/checkpoint.h"
#include "runtime/kernel_program.h"

namespace {

using Clock = std::chrono::steady_clock;

constexpr uint32_t kProbePixels = 64, kProbeSamples = 4;
constexpr double kGpuUnitSeconds = 0.075;  // 50-100 ms: long enough to amortise a launch, short for watchdogs

double seconds_since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

// What a device's thread reports to the render loop.
struct Event {
  enum Kind { ready, done, failed } kind = ready;
  uint32_t device = 0;
  uint64_t unit = 0;       // done, failed (0: the set-up failed)
  UnitOutput output;       // done
  uint64_t probe_hash = 0; // ready
  double probe_seconds = 0;
  std::string error;       // failed
  bool usage_error = false;
};

class EventQueue {
 public:
  void push(Event e) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      events_.push_back(std::move(e));
    }
    cv_.notify_one();
  }
  // The next event, waiting at most until `deadline`.
  std::optional<Event> pop(Clock::time_point deadline) {
    std::unique_lock<std::mutex> lock(mutex_);
    if (!cv_.wait_until(lock, deadline, [&] { return !events_.empty(); })) return std::nullopt;
    Event e = std::move(events_.front());
    events_.pop_front();
    return e;
  }

 private:
  std::mutex mutex_;
  std::condition_variable cv_;
  std::deque<Event> events_;
};

// A device's thread: prepares its worker (and probes it when the render has several devices), then runs
// the units it is given, one at a time, until told to stop.
class WorkerThread {
 public:
  struct Setup {
    const DeviceScene* scene;
    SceneHeader header;
    WorkerSettings settings;
    bool probe;
  };
  // make_worker runs in the new thread: the device's context is created, used and released there
  // (Oclgrind's uninitialised-value checker keeps thread-local state per context and crashes otherwise).
  WorkerThread(std::function<std::unique_ptr<UnitWorker>()> make_worker, uint32_t index, EventQueue& events,
               Setup setup)
      : index_(index), events_(events) {
    thread_ = std::thread([this, make_worker, setup] { run(make_worker, setup); });
  }
  ~WorkerThread() { stop(); }
  void submit(WorkUnit unit, std::vector<uint32_t> input) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      job_ = Job{unit, std::move(input)};
    }
    cv_.notify_one();
  }
  // Ends the thread after the unit it runs, if any.
  void stop() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      quit_ = true;
    }
    cv_.notify_one();
    if (thread_.joinable()) thread_.join();
  }
  UnitWorker& worker() { return *worker_; }

 private:
  struct Job {
    WorkUnit unit;
    std::vector<uint32_t> input;
  };
  void run(const std::function<std::unique_ptr<UnitWorker>()>& make_worker, const Setup& setup) {
    Event ready;
    ready.device = index_;
    try {
      worker_ = make_worker();
      worker_->prepare(*setup.scene, setup.header, setup.settings);
      if (setup.probe) {
        auto start = Clock::now();
        ready.probe_hash = worker_->probe(kProbePixels, kProbeSamples);
        ready.probe_seconds = seconds_since(start);
      }
    } catch (const std::exception& e) {
      ready.kind = Event::failed;
      ready.error = e.what();
      ready.usage_error = dynamic_cast<const UsageError*>(&e) != nullptr;
      events_.push(std::move(ready));
      return;
    }
    events_.push(std::move(ready));
    for (;;) {
      Job job;
      {
        std::unique_lock<std::mutex> lock(mutex_);
        cv_.wait(lock, [&] { return quit_ || job_.has_value(); });
        if (!job_) {  // quit, and nothing left to run
          worker_.reset();
          return;
        }
        job = std::move(*job_);
        job_.reset();
      }
      Event e;
      e.device = index_;
      e.unit = job.unit.id;
      try {
        e.output = worker_->run(job.unit, job.unit.upload ? &job.input : nullptr);
        e.kind = Event::done;
      } catch (const std::exception& ex) {
        e.kind = Event::failed;
        e.error = ex.what();
      }
      events_.push(std::move(e));
    }
  }

  std::unique_ptr<UnitWorker> worker_;
  uint32_t index_;
  EventQueue& events_;
  std::mutex mutex_;
  std::condition_variable cv_;
  std::optional<Job> job_;
  bool quit_ = false;
  std::thread thread_;
};

uint32_t next_power_of_two_above(uint32_t s) {
  uint64_t p = 1;
  while (p <= s) p *= 2;
  return uint32_t(std::min<uint64_t>(p, UINT32_MAX));
}

bool is_power_of_two(uint32_t s) { return s > 0 && (s & (s - 1)) == 0; }

RenderResult render_on(const std::vector<WorkerSource>& workers, const DeviceScene& scene,
                       const RenderOptions& options, const RenderCallbacks& callbacks) {
  RenderResult result;
  auto setup_start = Clock::now();
  const Technique& technique = technique_named(options.integrator, "integrator");
  check_technique_options(technique, options);
  SceneHeader header = scene.header;
  header.max_depth = options.max_depth;
  header.seed = options.seed;
  header.rr_depth = options.rr_depth;
  header.sampler = options.sampler;
  header.spp = options.spp;
  const uint32_t pixels = header.width * header.height;
  const size_t n = workers.size();
  const FilmLayout layout = make_film_layout(technique_layers(technique, options.max_depth), options.aovs, pixels);

  uint32_t start_spp = options.resume ? options.resume->spp : 0;
  if (options.resume && !(options.resume->layout == layout))
    throw RuntimeFailure("the film to resume from has the layers " + options.resume->layout.names() + " of " +
                         std::to_string(options.resume->layout.pixels) + " pixels, the render " + layout.names() +
                         " of " + std::to_string(pixels));
  // Techniques with emission: the light paths of a sample are numbered like the pixels (one per pixel),
  // and the schedule's tiles are runs of path indices.
  LightTransportSetup light_setup;
  if (uses_emission(technique)) light_setup = light_transport_setup(scene, options.spp);
  light_setup.header.only_strategy = options.debug_bdpt_strategy_s >= 0
                                         ? uint32_t(options.debug_bdpt_strategy_s) | uint32_t(options.debug_bdpt_strategy_t) << 16
                                         : PC_INVALID;
  if (technique.setup_light) technique.setup_light(light_setup, scene, options);
  if (technique.check_scene)
    for (std::string& w : technique.check_scene(scene)) result.warnings.push_back(std::move(w));
  result.light = light_setup.header;

  // Set-up on every device at once: kernel build (or cache), scene upload, and with several devices
  // the probe that tells their arithmetic classes apart.
  std::string build_options = kernel_options(options.all_features ? kFeatureAll : scene.features);
  if (options.debug_inject_hazards) build_options += " -DPC_DEBUG_INJECT_HAZARDS";
  if (options.debug_bias_diffuse) build_options += " -DPC_DEBUG_BIAS_DIFFUSE";
  if (options.build_nonce) build_options += " -DPC_BUILD_NONCE=" + std::to_string(options.build_nonce);
  EventQueue events;
  std::vector<std::unique_ptr<WorkerThread>> threads;
  result.devices.resize(n);
  std::vector<ScheduleDevice> schedule_devices(n);
  for (size_t d = 0; d < n; ++d) {
    const DeviceInfo& info = workers[d].info;
    DeviceReport& report = result.devices[d];
    report.name = info.name;
    report.platform = info.platform_name;
    report.sub_device = info.sub_device;
    report.compute_units = info.compute_units;
    report.rank = workers[d].rank;
    report.host = workers[d].host;
    double target = info.is_gpu ? kGpuUnitSeconds : technique.cpu_unit_seconds;
    if (workers[d].unit_seconds > 0) {
      target = std::max(target, workers[d].unit_seconds);
      schedule_devices[d].few_units = true;
    }
    if (options.time_budget > 0) target = std::min(target, options.time_budget / 20);  // overrun by a few percent at most
    schedule_devices[d].target_seconds = target;
    WorkerThread::Setup setup{&scene, header, {}, n > 1};
    WorkerSettings& ws = setup.settings;
    ws.technique = &technique;
    ws.layout = layout;
    const double origin[3] = {scene.origin.x, scene.origin.y, scene.origin.z};
    ws.aov = aov_header(layout, origin);
    ws.build_options = build_options;
    ws.work_group = options.work_group;
    ws.lanes = options.lanes;
    ws.light = &light_setup;
    ws.splat_pairs = options.debug_splat_pairs;
    ws.max_depth = options.max_depth;
    if (d < options.faults.size()) ws.fault = options.faults[d];
    threads.push_back(std::make_unique<WorkerThread>(workers[d].make, uint32_t(d), events, setup));
  }
  std::vector<bool> ready(n, false);
  std::vector<uint64_t> probe(n, 0);
  std::string first_error;
  bool usage_error = false;
  for (size_t pending = n; pending > 0; --pending) {
    Event e = *events.pop(Clock::time_point::max());
    DeviceReport& report = result.devices[e.device];
    if (e.kind == Event::failed) {
      report.used = false;
      report.note = "failed to start: " + e.error;
      if (first_error.empty()) first_error = e.error;
      usage_error |= e.usage_error;
      continue;
    }
    ready[e.device] = true;
    probe[e.device] = e.probe_hash;
    report.probe_seconds = e.probe_seconds;
    const WorkerReport w = threads[e.device]->worker().report();
    report.kernel_build_ms = w.kernel_build_ms;
    report.kernel_from_cache = w.kernel_from_cache;
    report.kernel_options = w.kernel_options;
    report.kernel_private_bytes = w.kernel_private_bytes;
    report.lanes = w.lanes;
    report.unit_items = w.unit_items;
    report.buffers = w.buffers;
    if (e.probe_seconds > 0) schedule_devices[e.device].rate = double(kProbePixels) * kProbeSamples / e.probe_seconds;
  }
  if (std::none_of(ready.begin(), ready.end(), [](bool r) { return r; })) {
    if (usage_error) throw UsageError(first_error);
    throw RuntimeFailure(first_error);
  }
  // The host's film only now: a film too large for every device has been refused without the seconds
  // that allocating and clearing gigabytes on the host take.
  Film film = options.resume ? *options.resume : make_film(header.width, header.height, technique.name, layout);
  result.kernel_from_cache = true;
  for (size_t d = 0; d < n; ++d) {
    if (!ready[d]) continue;
    const DeviceReport& r = result.devices[d];
    result.kernel_build_ms = std::max(result.kernel_build_ms, r.kernel_build_ms);
    result.kernel_from_cache &= r.kernel_from_cache;
    if (result.kernel_options.empty()) result.kernel_options = r.kernel_options;
  }

  // Arithmetic classes: devices whose probe differs from the first ready device's compute other bits.
  size_t reference = std::find(ready.begin(), ready.end(), true) - ready.begin();
  std::vector<uint64_t> classes{probe[reference]};
  for (size_t d = 0; d < n; ++d) {
    if (!ready[d]) continue;
    auto it = std::find(classes.begin(), classes.end(), probe[d]);
    result.devices[d].arithmetic_class = uint32_t(it - classes.begin());
    if (it == classes.end()) classes.push_back(probe[d]);
  }
  if (options.allow_mixed_devices && classes.size() > 1) result.determinism = "mixed";
  for (size_t d = 0; d < n; ++d) schedule_devices[d].mixed_class = result.devices[d].arithmetic_class != 0;
  // Units no larger than every device's buffers take (each worker's unit_items), nor than asked.
  uint32_t unit_limit = options.max_unit_pixels > 0 ? options.max_unit_pixels : pixels;
  size_t ready_devices = 0;
  for (size_t d = 0; d < n; ++d)
    if (ready[d]) {
      ++ready_devices;
      if (result.devices[d].unit_items > 0) unit_limit = std::min(unit_limit, result.devices[d].unit_items);
    }
  // A per-sample technique's unit traces every camera path of its iteration whatever its share of the light
  // paths (the merging integrators): by default a device's tile is its share of the image, as large as its
  // buffers allow, so that one device runs whole iterations.
  uint32_t tile_pixels = options.tile_pixels > 0 ? options.tile_pixels : RenderSchedule::default_tile_pixels(pixels);
  if (options.tile_pixels == 0 && technique.per_sample)
    tile_pixels = std::min<uint32_t>(unit_limit, uint32_t((pixels + ready_devices - 1) / std::max<size_t>(ready_devices, 1)));
  RenderSchedule schedule(pixels, tile_pixels, start_spp, schedule_devices);
  for (size_t d = 0; d < n; ++d) {
    DeviceReport& report = result.devices[d];
    if (!ready[d]) {
      schedule.remove_device(uint32_t(d), report.note);
      result.warnings.push_back(report.name + ": " + report.note + "; rendering on the other devices");
    } else if (report.arithmetic_class != 0 && !options.allow_mixed_devices) {
      report.used = false;
      report.note = "left out: its probe render differs from " + result.devices[reference].name +
                    "'s (another arithmetic class); --allow-mixed-devices uses it anyway";
      schedule.remove_device(uint32_t(d), report.note);
      result.warnings.push_back(report.name + ": " + report.note);
    }
  }
  if (options.pass_spp > 0) schedule.fix_samples_per_unit(options.pass_spp);
  if (unit_limit < pixels) schedule.limit_unit_pixels(unit_limit);
  result.setup_seconds = seconds_since(setup_start);

  // The render: hand units to idle devices, copy finished ones into the film, stop at a horizon.
  auto start = Clock::now();
  auto now = [&] { return seconds_since(start); };
  auto next_horizon = [&](uint32_t s) {
    uint32_t h = options.spp;
    if (options.power_of_two_horizons || options.target_error > 0) h = std::min(h, next_power_of_two_above(s));
    return std::max(h, s);
  };
  schedule.set_horizon(next_horizon(start_spp));
  std::map<uint64_t, UnitOutput> kept;  // committed results whose copies still run
  std::vector<bool> busy(n, false);
  double last_checkpoint = 0;
  bool closing = false;
  const uint64_t samples_total = uint64_t(pixels) * options.spp;
  auto checkpoint_due = [&] { return !options.checkpoint.empty() && now() - last_checkpoint >= options.checkpoint_every; };
  auto interrupted = [&] { return options.interrupt && *options.interrupt; };
  auto time_is_up = [&] { return options.time_budget > 0 && now() >= options.time_budget; };
  uint64_t sum_overflows = 0;  // commutative sums that wrapped past 2^64 on the host
  // The film at the schedule's level, developed by the technique (and its AOVs).
  auto make_film = [&] {
    Film f = film;
    f.spp = schedule.lowest_level();
    uint64_t top_bit = 0;  // sums at or above 2^63
    technique.develop(f, light_setup.header, &top_bit);
    if (uses_emission(technique)) result.splat_overflows = std::max(result.splat_overflows, top_bit + sum_overflows);
    develop_aovs(f);
    return f;
  };
  auto write_checkpoint_now = [&](const Film& f) {
    write_checkpoint(options.checkpoint, options.checkpoint_key, f);
    last_checkpoint = now();
    result.checkpoint_spp = f.spp;
  };
  // A committed unit into the film: its ordered layers' pixels copied over the film's, its commutative
  // layers added as 64-bit integers (exact, and the same total in any order of units and devices).
  auto commit = [&](const WorkUnit& unit, const UnitOutput& out) {
    for (size_t layer = 0; layer < layout.layers.size(); ++layer) {
      const FilmLayout::UnitPart part = layout.unit_part(layer, unit.pixel_begin, unit.pixel_count);
      if (layout.layers[layer].kind == PC_LAYER_ORDERED) {
        const uint32_t* from = out.ordered.data() + part.payload_offset;
        std::copy(from, from + part.words, film.words.begin() + part.film_offset);
        continue;
      }
      for (size_t i = 0; i < part.words; i += 2) {
        uint32_t* to = film.words.data() + part.film_offset + i;
        const uint32_t* add = out.commutative.data() + part.payload_offset + i;
        uint64_t a = uint64_t(to[1]) << 32 | to[0], b = uint64_t(add[1]) << 32 | add[0], sum = a + b;
        sum_overflows += sum < a;
        to[0] = uint32_t(sum);
        to[1] = uint32_t(sum >> 32);
      }
    }
  };
  auto handle = [&](Event& e) {
    busy[e.device] = false;
    DeviceReport& report = result.devices[e.device];
    if (e.kind == Event::failed) {
      const WorkUnit* u = schedule.running(e.unit);
      if (u) schedule.fail(e.unit, "failed: " + e.error);
      report.note = "failed after " + std::to_string(report.units) + " units: " + e.error;
      result.warnings.push_back(report.name + " " + report.note + "; its units go to the other devices");
      return;
    }
    const WorkUnit unit = *schedule.running(e.unit);
    UnitFinish f = schedule.finish(e.unit, e.output.seconds);
    report.kernel_seconds += e.output.kernel_ms * 1e-3;
    report.transfer_seconds += std::max(0.0, e.output.seconds - e.output.kernel_ms * 1e-3);
    report.transfer_bytes += e.output.transfer_bytes;
    result.kernel_ms += e.output.kernel_ms;
    result.launches++;
    for (const PhaseTime& p : e.output.phases) {
      auto it = std::find_if(result.phases.begin(), result.phases.end(), [&](const PhaseTime& q) { return q.name == p.name; });
      if (it == result.phases.end()) result.phases.push_back(p);
      else it->ms += p.ms;
    }
    if (f.outcome == UnitOutcome::committed) {
      commit(unit, e.output);
      result.splat_overflows += e.output.splat_overflows;
      result.light_vertices += e.output.light_vertices;
      const UnitStats& s = e.output.stats;
      result.rays += uint64_t(s.rays_hi) << 32 | s.rays_lo;
      result.nan_samples += s.nan_samples;
      result.inf_samples += s.inf_samples;
      result.negative_samples += s.negative_samples;
      if (f.twin != 0) kept[e.unit] = std::move(e.output);
      if (callbacks.progress) callbacks.progress(schedule.samples_done(), samples_total, now());
    } else if (f.outcome == UnitOutcome::compare) {
      auto twin = kept.find(f.twin);
      bool same = twin->second.ordered == e.output.ordered && twin->second.commutative == e.output.commutative;
      kept.erase(twin);
      if (!same)
        throw RuntimeFailure(report.name + " and another device of the same arithmetic class computed different bits "
                             "for pixels " + std::to_string(unit.pixel_begin) + "-" +
                             std::to_string(unit.pixel_begin + unit.pixel_count - 1) + ", samples " +
                             std::to_string(unit.sample_begin) + "-" +
                             std::to_string(unit.sample_begin + unit.sample_count - 1) + ": a determinism bug");
      result.duplicate_checks++;
    } else if (f.twin != 0) {
      kept.erase(f.twin);
    }
  };

  for (;;) {
    for (size_t d = 0; d < n; ++d) {
      if (!ready[d] || busy[d]) continue;
      std::optional<WorkUnit> u = schedule.next_unit(uint32_t(d), now());
      if (!u) continue;
      // The ordered layers' words of the unit's pixels (commutative layers start from cleared sums).
      std::vector<uint32_t> input;
      if (u->upload)
        for_each_unit_part(layout, PC_LAYER_ORDERED, u->pixel_begin, u->pixel_count, [&](const FilmLayout::UnitPart& p) {
          auto from = film.words.begin() + p.film_offset;
          input.insert(input.end(), from, from + p.words);
        });
      busy[d] = true;
      threads[d]->submit(*u, std::move(input));
    }
    if (schedule.at_horizon()) {
      result.horizons++;
      uint32_t spp = schedule.horizon();
      std::optional<Film> f;
      auto film_now = [&]() -> const Film& {
        if (!f) f = make_film();
        return *f;
      };
      if (callbacks.horizon && is_power_of_two(spp) && options.power_of_two_horizons) callbacks.horizon(film_now(), now(), result.kernel_build_ms);
      std::string stop;
      if (spp >= options.spp) stop = "spp";
      else if (interrupted()) stop = "interrupted";
      // The half-image estimate needs a few samples in each half before it can be trusted.
      else if (options.target_error > 0 && spp >= 8 && is_power_of_two(spp) && estimated_rel_mse(film_now()) < options.target_error)
        stop = "target_error";
      else if (time_is_up()) stop = "time";
      if (!options.checkpoint.empty() && (checkpoint_due() || (!stop.empty() && result.checkpoint_spp != spp)))
        write_checkpoint_now(film_now());
      if (!stop.empty()) {
        result.stop_reason = stop;
        break;
      }
      schedule.set_horizon(next_horizon(spp));
      closing = false;
      continue;
    }
    if (schedule.idle()) {
      if (!schedule.any_active_device()) {
        std::string why;
        for (const DeviceReport& r : result.devices) why += "\n  " + r.name + ": " + r.note;
        throw RuntimeFailure("every device failed:" + why);
      }
      throw std::logic_error("render loop: no unit running, none to start, and the film is not at the horizon");
    }
    // Wake for the next event, or when a deadline asks for the pass to be closed.
    Clock::time_point deadline = Clock::now() + std::chrono::milliseconds(closing ? 1000 : 20);
    if (options.time_budget > 0 && !closing)
      deadline = std::min(deadline, start + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(options.time_budget)));
    if (std::optional<Event> e = events.pop(deadline)) handle(*e);
    if (!closing && (interrupted() || time_is_up() || checkpoint_due())) {
      schedule.close_pass();
      closing = true;
    }
  }
  // Copies still running are waited for and compared: they are the identity check.
  while (!schedule.idle()) {
    Event e = *events.pop(Clock::time_point::max());
    handle(e);
  }
  result.render_seconds = now();
  for (auto& t : threads) t->stop();

  result.film = make_film();
  const auto& stats = schedule.device_stats();
  for (size_t d = 0; d < n; ++d) {
    DeviceReport& r = result.devices[d];
    const ScheduleDeviceStats& s = stats[d];
    r.units = s.units;
    r.samples = s.samples;
    r.duplicates_run = s.duplicates_run;
    r.duplicates_won = s.duplicates_won;
    r.failures = s.failures;
    r.busy_seconds = s.busy_seconds;
    r.idle_seconds = r.used ? std::max(0.0, result.render_seconds - s.busy_seconds) : 0;
    if (s.dropped) r.note = s.left_because;
    if (r.used && s.finished == 0 && r.note.empty()) r.note = "no unit was left for it";
  }
  return result;
}

}  // namespace

RenderResult render(const std::vector<DeviceInfo>& devices, const DeviceScene& scene, const RenderOptions& options,
                    const RenderCallbacks& callbacks) {
  return render(device_workers(devices), scene, options, callbacks);
}

std::vector<WorkerSource> device_workers(const std::vector<DeviceInfo>& devices) {
  bool has_gpu = std::any_of(devices.begin(), devices.end(), [](const DeviceInfo& d) { return d.is_gpu; });
  std::vector<WorkerSource> workers;
  for (const DeviceInfo& d : devices) {
    DeviceInfo use = has_gpu && d.is_cpu && d.compute_units > 1 ? partition_device(d, d.compute_units - 1) : d;
    workers.push_back({use, [use] { return std::make_unique<DeviceWorker>(use); }, 0, {}, 0});
  }
  return workers;
}

RenderResult render(const std::vector<WorkerSource>& workers, const DeviceScene& scene, const RenderOptions& options,
                    const RenderCallbacks& callbacks) {
  if (workers.empty()) throw UsageError("no device to render on");
  return render_on(workers, scene, options, callbacks);
}

RenderResult render(ClContext& cl, const DeviceScene& scene, const RenderOptions& options,
                    const RenderCallbacks& callbacks) {
  return render_on({{cl.info, [&cl] { return std::make_unique<DeviceWorker>(cl); }, 0, {}, 0}}, scene, options, callbacks);
}
