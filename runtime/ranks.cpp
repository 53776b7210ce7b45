#include "runtime/ranks.h"

#include <cstdlib>
#include <string>

#include <unistd.h>

#include "runtime/errors.h"

namespace {

// The number of processes of the job this process was launched in by mpirun or mpiexec (Open MPI's
// OMPI_COMM_WORLD_SIZE, Hydra's and Slurm's PMI_SIZE), 0 if none; -1 when a PMIx launcher (srun --mpi=pmix)
// started it without saying how many.
int launched_ranks() {
  for (const char* name : {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE"})
    if (const char* v = std::getenv(name)) return std::atoi(v);
  return std::getenv("PMIX_RANK") ? -1 : 0;
}

}  // namespace

std::string host_name() {
  char name[256] = {};
  gethostname(name, sizeof name - 1);
  return name;
}

#ifndef PATHCL_MPI

struct RankJob::Impl {};

RankJob::RankJob(int*, char***) {
  if (launched_ranks() > 1)
    throw UsageError("this pathcl was built without MPI (CMake found no MPI library), so it cannot render as one of " +
                     std::to_string(launched_ranks()) + " ranks: install libopenmpi-dev and rebuild, or run one process");
}
RankJob::~RankJob() = default;
std::vector<WorkerSource> RankJob::remote_workers(double, std::vector<std::string>*) { return {}; }
std::vector<RankJob::LostRank> RankJob::lost_ranks() const { return {}; }
void RankJob::finish() {}
int RankJob::serve(const std::string&, const Faults&) { return 0; }

#else

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <csignal>
#include <cstdio>
#include <deque>
#include <exception>
#include <map>
#include <mutex>
#include <optional>
#include <thread>

#include <mpi.h>

#include "runtime/device_worker.h"
#include "runtime/rank_messages.h"

namespace {

using Clock = std::chrono::steady_clock;

// Message tags. Rank-wide messages below 8; a device's requests and its answers at kind + 8 (device + 1).
enum : int { kTagHello = 1, kTagScene = 2, kTagQuit = 3 };
enum : int { kPrepare = 1, kProbe = 2, kRun = 3, kAnswer = 7 };
int device_tag(int kind, uint32_t device) { return kind + 8 * int(device + 1); }

constexpr uint64_t kChunkBytes = uint64_t(1) << 30;         // MPI counts are ints: large messages in parts
constexpr uint64_t kMaxMessageBytes = uint64_t(1) << 40;    // a size beyond this is garbage
constexpr auto kPoll = std::chrono::microseconds(500);      // waits poll (Open MPI's blocking calls spin)
constexpr double kSetupSeconds = 600;  // a kernel build and the scene's upload, beside --rank-timeout
// A remote device's units: long enough that their fixed cost (a few ms of messages and wake-ups) and their
// pixels' results (48 bytes a pixel for path, however many samples the unit added) stay a small part of
// their time: 2 s on CPUs carry about 2 % (docs/ranks.md); shorter on GPUs, whose drivers may stop kernels
// of a few seconds.
constexpr double kRemoteCpuUnitSeconds = 2.0, kRemoteGpuUnitSeconds = 0.5;

// An error an MPI call returned (MPI_ERRORS_RETURN).
struct MpiError : RuntimeFailure {
  using RuntimeFailure::RuntimeFailure;
};

void check_mpi(int rc, const char* what) {
  if (rc == MPI_SUCCESS) return;
  char text[MPI_MAX_ERROR_STRING];
  int length = 0;
  MPI_Error_string(rc, text, &length);
  throw MpiError(std::string(what) + ": " + std::string(text, length));
}

using Bytes = std::vector<uint8_t>;

// The buffers of sends given up at their deadline (a receiver that is gone): MPI may still read them, so they
// are kept until the process ends.
std::mutex abandoned_mutex;
std::vector<std::shared_ptr<const void>> abandoned;

// Polls a request until it completes (true) or `deadline` passes (false: it is left pending). `sleep`: wait
// 0.5 ms between polls, for a message that may take long to start (Open MPI's blocking calls spin); else
// yield only, for one known to be on its way, since Open MPI moves a large message's fragments only while both
// sides call into it (sleeping between polls made a 1.6 MB result take 15 ms).
bool poll_until(MPI_Request& request, Clock::time_point deadline, bool sleep) {
  for (;;) {
    int done = 0;
    check_mpi(MPI_Test(&request, &done, MPI_STATUS_IGNORE), "MPI_Test");
    if (done) return true;
    if (Clock::now() >= deadline) return false;
    if (sleep) std::this_thread::sleep_for(kPoll);
    else std::this_thread::yield();
  }
}

// A message: its size, then its bytes in parts, all with one tag (MPI keeps their order). False when the
// receiver has not taken it by `deadline`.
bool send_bytes(int to, int tag, std::shared_ptr<const Bytes> bytes, Clock::time_point deadline) {
  auto size = std::make_shared<const uint64_t>(bytes->size());
  MPI_Request request;
  check_mpi(MPI_Isend(size.get(), 1, MPI_UINT64_T, to, tag, MPI_COMM_WORLD, &request), "MPI_Isend");
  bool sent = poll_until(request, deadline, false);
  for (uint64_t at = 0; sent && at < *size; at += kChunkBytes) {
    check_mpi(MPI_Isend(bytes->data() + at, int(std::min(kChunkBytes, *size - at)), MPI_BYTE, to, tag, MPI_COMM_WORLD,
                        &request),
              "MPI_Isend");
    sent = poll_until(request, deadline, false);
  }
  if (!sent) {
    std::lock_guard<std::mutex> lock(abandoned_mutex);
    abandoned.push_back(size);
    abandoned.push_back(bytes);
  }
  return sent;
}

bool send_bytes(int to, int tag, Bytes bytes, Clock::time_point deadline = Clock::time_point::max()) {
  return send_bytes(to, tag, std::make_shared<const Bytes>(std::move(bytes)), deadline);
}

// A receive given up: cancelled, so that no late message lands in its buffer.
void cancel_receive(MPI_Request& request) {
  MPI_Cancel(&request);
  MPI_Wait(&request, MPI_STATUS_IGNORE);
}

// A receive completed by `deadline`, or cancelled (false).
bool received_by(MPI_Request& request, Clock::time_point deadline, bool sleep) {
  if (poll_until(request, deadline, sleep)) return true;
  cancel_receive(request);
  return false;
}

// The bytes of a message whose size came (receive_bytes, AnswerCourier), or nothing if they have not come by
// `deadline`.
std::optional<Bytes> receive_body(int from, int tag, uint64_t n, Clock::time_point deadline) {
  if (n > kMaxMessageBytes) throw RankMessageError("a message of " + std::to_string(n) + " bytes");
  Bytes bytes(n);
  MPI_Request request;
  for (uint64_t at = 0; at < n; at += kChunkBytes) {
    check_mpi(MPI_Irecv(bytes.data() + at, int(std::min(kChunkBytes, n - at)), MPI_BYTE, from, tag, MPI_COMM_WORLD, &request),
              "MPI_Irecv");
    if (!received_by(request, deadline, false)) return std::nullopt;
  }
  return bytes;
}

// A message sent with send_bytes, or nothing if it has not come whole by `deadline`.
std::optional<Bytes> receive_bytes(int from, int tag, Clock::time_point deadline) {
  uint64_t n = 0;
  MPI_Request request;
  check_mpi(MPI_Irecv(&n, 1, MPI_UINT64_T, from, tag, MPI_COMM_WORLD, &request), "MPI_Irecv");
  if (!received_by(request, deadline, true)) return std::nullopt;
  return receive_body(from, tag, n, deadline);
}

// Rank 0's answers from every remote device, received by one thread: a device's thread waits on a condition
// instead of polling MPI itself, so that rank 0 wakes every 0.5 ms once, not once for each remote device.
class AnswerCourier {
 public:
  AnswerCourier() : thread_([this] { run(); }) {}
  ~AnswerCourier() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      quit_ = true;
    }
    work_.notify_all();
    thread_.join();
  }
  // As receive_bytes.
  std::optional<Bytes> receive(int from, int tag, Clock::time_point deadline) {
    auto wait = std::make_shared<Wait>();
    wait->from = from;
    wait->tag = tag;
    wait->deadline = deadline;
    check_mpi(MPI_Irecv(&wait->size, 1, MPI_UINT64_T, from, tag, MPI_COMM_WORLD, &wait->header), "MPI_Irecv");
    std::unique_lock<std::mutex> lock(mutex_);
    waits_.push_back(wait);
    work_.notify_all();
    done_.wait(lock, [&] { return wait->finished; });
    if (wait->error) std::rethrow_exception(wait->error);
    return std::move(wait->bytes);
  }

 private:
  struct Wait {
    int from = 0, tag = 0;
    Clock::time_point deadline;
    uint64_t size = 0;
    MPI_Request header = MPI_REQUEST_NULL;
    bool finished = false;
    std::optional<Bytes> bytes;
    std::exception_ptr error;
  };
  void run() {
    std::unique_lock<std::mutex> lock(mutex_);
    for (;;) {
      work_.wait(lock, [&] { return quit_ || !waits_.empty(); });
      if (waits_.empty()) return;  // quit, with nobody waiting
      bool finished = false;
      for (auto it = waits_.begin(); it != waits_.end();) {
        Wait& w = **it;
        try {
          int done = 0;
          check_mpi(MPI_Test(&w.header, &done, MPI_STATUS_IGNORE), "MPI_Test");
          if (!done && Clock::now() < w.deadline) {
            ++it;
            continue;
          }
          if (done) {
            w.bytes = receive_body(w.from, w.tag, w.size, w.deadline);
          } else {
            cancel_receive(w.header);
          }
        } catch (...) {
          w.error = std::current_exception();
        }
        w.finished = finished = true;
        it = waits_.erase(it);
      }
      if (finished) done_.notify_all();
      if (!waits_.empty()) {
        lock.unlock();
        std::this_thread::sleep_for(kPoll);
        lock.lock();
      }
    }
  }

  std::mutex mutex_;
  std::condition_variable work_, done_;
  std::vector<std::shared_ptr<Wait>> waits_;
  bool quit_ = false;
  std::thread thread_;
};

Clock::time_point after(double seconds) {
  return Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(seconds));
}

double seconds_since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

// Rank 0's view of another rank.
struct RankLink {
  int rank = 0;
  std::string host;
  std::vector<RankDevice> devices;
  std::mutex mutex;
  bool scene_sent = false;
  std::string lost;  // why it was given up, once it was
  std::string who() const { return "rank " + std::to_string(rank) + " (" + host + ")"; }
};

}  // namespace

struct RankJob::Impl {
  bool initialised = false;  // MPI_Init_thread was called (and MPI_Finalize is due)
  // A rank of the job was lost: MPI_Finalize is skipped. Open MPI's finalize is a fence over every process
  // of the job, the dead one too: under --enable-recovery it spins there for good when the process's death
  // has not reached the runtime first (seen as a hang of rank 0 and the other live ranks, 1 run in ~20).
  bool rank_lost = false;
  std::unique_ptr<AnswerCourier> courier;  // while remote devices render
  std::vector<std::unique_ptr<RankLink>> links;  // ranks 1 .. K-1
  double timeout = 30;
  bool finished = false;
  std::mutex scene_mutex;
  const DeviceScene* encoded_scene = nullptr;
  std::shared_ptr<const Bytes> scene_bytes;

  // The device scene to a rank, once (the first of its workers to prepare sends it; the others wait); false
  // when the rank has not taken it by `deadline`.
  bool send_scene(RankLink& link, const DeviceScene& scene, Clock::time_point deadline) {
    std::lock_guard<std::mutex> lock(link.mutex);
    if (link.scene_sent) return true;
    std::shared_ptr<const Bytes> bytes;
    {
      std::lock_guard<std::mutex> encode_lock(scene_mutex);
      if (encoded_scene != &scene) {
        scene_bytes = std::make_shared<const Bytes>(encode_scene(scene));
        encoded_scene = &scene;
      }
      bytes = scene_bytes;
    }
    link.scene_sent = send_bytes(link.rank, kTagScene, bytes, deadline);
    return link.scene_sent;
  }
  void lose(RankLink& link, const std::string& why) {
    std::lock_guard<std::mutex> lock(link.mutex);
    if (link.lost.empty()) link.lost = why;
  }
  std::string lost_why(RankLink& link) const {
    std::lock_guard<std::mutex> lock(link.mutex);
    return link.lost;
  }
};

namespace {

// A device of another rank as a unit worker of rank 0's render loop: each call is a request and its
// answer, waited for with a deadline.
class RemoteWorker : public UnitWorker {
 public:
  RemoteWorker(RankJob::Impl& job, RankLink& link, uint32_t device) : job_(job), link_(link), device_(device) {
    who_ = link.who() + " device " + std::to_string(device);
  }
  void prepare(const DeviceScene& scene, const SceneHeader& header, const WorkerSettings& settings) override {
    layout_ = settings.layout;
    const double seconds = job_.timeout + kSetupSeconds;
    check_not_lost();
    if (!job_.send_scene(link_, scene, after(seconds))) lose("it did not take the device scene within " + whole(seconds) + " s");
    exchange(kPrepare, encode_setup(header, settings), seconds, "its set-up",
             [&](const Bytes& b) { report_ = decode_report(b, who_); });
  }
  uint64_t probe(uint32_t count, uint32_t spp) override {
    uint64_t hash = 0;
    auto start = Clock::now();
    exchange(kProbe, encode_probe_request(count, spp), job_.timeout + kSetupSeconds, "the probe",
             [&](const Bytes& b) { hash = decode_probe(b, who_); });
    seconds_per_sample_ = seconds_since(start) / std::max(1.0, double(count) * spp);
    return hash;
  }
  UnitOutput run(const WorkUnit& unit, const std::vector<uint32_t>* input) override {
    const double samples = double(unit.pixel_count) * unit.sample_count;
    // Its expected time from the probe and the units before (the slowest rate seen lately), four times over.
    const double expected = seconds_per_sample_ > 0 ? seconds_per_sample_ * samples : kSetupSeconds;
    UnitOutput out;
    Bytes request = encode_unit(unit, input);
    uint64_t bytes = request.size();
    auto start = Clock::now();
    exchange(kRun, std::move(request), job_.timeout + 4 * expected, "unit " + std::to_string(unit.id), [&](const Bytes& b) {
      bytes += b.size();
      out = decode_output(b, who_);
      const size_t ordered = layout_.words_per_pixel(PC_LAYER_ORDERED) * unit.pixel_count;
      const size_t commutative = layout_.words_per_pixel(PC_LAYER_COMMUTATIVE) * layout_.pixels;
      if (out.ordered.size() != ordered || out.commutative.size() != commutative)
        throw RankMessageError("its result of unit " + std::to_string(unit.id) + " has " +
                               std::to_string(out.ordered.size()) + " + " + std::to_string(out.commutative.size()) +
                               " words, not " + std::to_string(ordered) + " + " + std::to_string(commutative));
    });
    out.seconds = seconds_since(start);
    out.transfer_bytes = bytes;
    const double rate = out.seconds / std::max(1.0, samples);
    seconds_per_sample_ = std::max(rate, seconds_per_sample_ * 0.5);
    return out;
  }
  WorkerReport report() const override { return report_; }

 private:
  // Sends a request and reads its answer with `read`, both by `seconds` from now. The rank is lost when it
  // does not take the request or answer in time, or answers garbage; a worker that fails (a kernel build)
  // answers an error, which is thrown without losing the rank.
  template <class Read>
  void exchange(int kind, Bytes request, double seconds, const std::string& what, Read&& read) {
    check_not_lost();
    const Clock::time_point deadline = after(seconds);
    std::optional<Bytes> answer;
    try {
      if (!send_bytes(link_.rank, device_tag(kind, device_), std::move(request), deadline))
        lose("it did not take " + what + " within " + whole(seconds) + " s");
      answer = job_.courier->receive(link_.rank, device_tag(kAnswer, device_), deadline);
    } catch (const RankMessageError& e) {
      lose(std::string("sent garbage: ") + e.what());
    } catch (const MpiError& e) {
      lose(e.what());
    }
    if (!answer) lose("no answer to " + what + " within " + whole(seconds) + " s");
    try {
      read(*answer);
    } catch (const RankMessageError& e) {
      lose(std::string("sent garbage: ") + e.what());
    }
  }
  void check_not_lost() {
    if (std::string why = job_.lost_why(link_); !why.empty()) throw RuntimeFailure(link_.who() + " was lost: " + why);
  }
  static std::string whole(double seconds) {
    char text[32];
    std::snprintf(text, sizeof text, "%.0f", seconds);
    return text;
  }
  [[noreturn]] void lose(const std::string& why) {
    job_.lose(link_, why);
    throw RuntimeFailure(link_.who() + " is lost: " + why);
  }

  RankJob::Impl& job_;
  RankLink& link_;
  uint32_t device_;
  std::string who_;
  FilmLayout layout_;
  WorkerReport report_;
  double seconds_per_sample_ = 0;
};

// A rank's device, serving rank 0's requests in a thread of its own, one at a time.
class DeviceServer {
 public:
  DeviceServer(const DeviceInfo& info, uint32_t device, std::shared_ptr<const DeviceScene>* scene,
               std::string* scene_error, const RankJob::Faults& faults, std::atomic<int64_t>* units_answered)
      : info_(info), device_(device), scene_(scene), scene_error_(scene_error), faults_(faults), units_(units_answered) {
    thread_ = std::thread([this] { serve(); });
  }
  ~DeviceServer() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      quit_ = true;
    }
    cv_.notify_one();
    thread_.join();
  }
  // scene: the device scene as received, read when a prepare request comes (the main thread sets it
  // before it reads any request after it).
  void push(int kind, Bytes bytes) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      jobs_.push_back({kind, std::move(bytes)});
    }
    cv_.notify_one();
  }

 private:
  void serve() {
    for (;;) {
      std::pair<int, Bytes> job;
      {
        std::unique_lock<std::mutex> lock(mutex_);
        cv_.wait(lock, [&] { return quit_ || !jobs_.empty(); });
        if (quit_) break;
        job = std::move(jobs_.front());
        jobs_.pop_front();
      }
      Bytes answer;
      try {
        answer = handle(job.first, job.second);
      } catch (const UsageError& e) {
        answer = encode_error(e.what(), true);
      } catch (const std::exception& e) {
        answer = encode_error(e.what(), false);
      }
      try {
        send_bytes(0, device_tag(kAnswer, device_), std::move(answer));
      } catch (const std::exception& e) {
        std::fprintf(stderr, "error: %s\n", e.what());
      }
    }
    worker_.reset();  // the context is released in the thread that made it
  }
  Bytes handle(int kind, const Bytes& bytes) {
    if (kind == kPrepare) {
      setup_ = std::make_unique<WorkerSetupMessage>();
      decode_setup(bytes, *setup_);
      setup_->settings.fault.perturb |= faults_.perturb;
      if (!*scene_) throw RuntimeFailure("no device scene came: " + *scene_error_);
      worker_.reset();
      worker_ = std::make_unique<DeviceWorker>(info_);
      worker_->prepare(**scene_, setup_->header, setup_->settings);
      return encode_report(worker_->report());
    }
    if (!worker_) throw RuntimeFailure("a request before the worker's set-up");
    if (kind == kProbe) {
      uint32_t count = 0, spp = 0;
      decode_probe_request(bytes, &count, &spp);
      return encode_probe(worker_->probe(count, spp));
    }
    if (kind != kRun) throw RankMessageError("a request of unknown kind " + std::to_string(kind));
    if (faults_.kill_after_units >= 0 && *units_ >= faults_.kill_after_units) kill(getpid(), SIGKILL);  // tests: a lost node
    if (faults_.unit_delay > 0) std::this_thread::sleep_for(std::chrono::duration<double>(faults_.unit_delay));
    std::vector<uint32_t> input;
    WorkUnit unit = decode_unit(bytes, input);
    Bytes answer = encode_output(worker_->run(unit, unit.upload ? &input : nullptr));
    if (faults_.corrupt_answers) answer[answer.size() / 2] ^= 1;
    ++*units_;
    return answer;
  }

  DeviceInfo info_;
  uint32_t device_;
  std::shared_ptr<const DeviceScene>* scene_;
  std::string* scene_error_;
  RankJob::Faults faults_;
  std::atomic<int64_t>* units_;
  std::unique_ptr<WorkerSetupMessage> setup_;  // the worker's settings point into it
  std::unique_ptr<DeviceWorker> worker_;
  std::mutex mutex_;
  std::condition_variable cv_;
  std::deque<std::pair<int, Bytes>> jobs_;
  bool quit_ = false;
  std::thread thread_;
};

}  // namespace

RankJob::RankJob(int* argc, char*** argv) : impl_(std::make_unique<Impl>()) {
  if (launched_ranks() == 0) return;
  int provided = 0;
  check_mpi(MPI_Init_thread(argc, argv, MPI_THREAD_MULTIPLE, &provided), "MPI_Init_thread");
  impl_->initialised = true;
  MPI_Comm_set_errhandler(MPI_COMM_WORLD, MPI_ERRORS_RETURN);
  MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
  MPI_Comm_size(MPI_COMM_WORLD, &size_);
  if (provided < MPI_THREAD_MULTIPLE && size_ > 1) {
    MPI_Finalize();
    impl_->initialised = false;
    throw RuntimeFailure("the MPI library does not support MPI_THREAD_MULTIPLE, which pathcl's ranks need");
  }
}

RankJob::~RankJob() {
  if (!impl_->initialised) return;
  try {
    finish();
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
  }
  if (!impl_->rank_lost) MPI_Finalize();
}

std::vector<WorkerSource> RankJob::remote_workers(double timeout_seconds, std::vector<std::string>* warnings) {
  impl_->timeout = timeout_seconds;
  if (size_ > 1) impl_->courier = std::make_unique<AnswerCourier>();
  std::vector<WorkerSource> workers;
  for (int r = 1; r < size_; ++r) {
    auto link = std::make_unique<RankLink>();
    link->rank = r;
    link->host = "rank " + std::to_string(r);
    std::optional<Bytes> bytes;
    std::string error;
    try {
      bytes = receive_bytes(r, kTagHello, after(timeout_seconds + kSetupSeconds));
      if (!bytes) error = "no list of devices came";
      else {
        RankHello hello = decode_hello(*bytes);
        link->host = hello.host;
        link->devices = hello.devices;
        error = hello.error;
      }
    } catch (const std::exception& e) {
      error = e.what();
    }
    if (!error.empty() || link->devices.empty()) {
      if (error.empty()) error = "it has no device";
      impl_->lose(*link, error);
      warnings->push_back(link->who() + " renders nothing: " + error);
    }
    for (uint32_t d = 0; d < link->devices.size() && error.empty(); ++d) {
      WorkerSource s;
      s.info = device_info(link->devices[d]);
      s.rank = uint32_t(r);
      s.host = link->host;
      s.unit_seconds = s.info.is_gpu ? kRemoteGpuUnitSeconds : kRemoteCpuUnitSeconds;
      RankLink* l = link.get();
      Impl* job = impl_.get();
      s.make = [job, l, d] { return std::make_unique<RemoteWorker>(*job, *l, d); };
      workers.push_back(std::move(s));
    }
    impl_->links.push_back(std::move(link));
  }
  return workers;
}

std::vector<RankJob::LostRank> RankJob::lost_ranks() const {
  std::vector<LostRank> lost;
  for (const auto& link : impl_->links)
    if (std::string why = impl_->lost_why(*link); !why.empty()) lost.push_back({link->rank, link->who() + ": " + why});
  return lost;
}

void RankJob::finish() {
  if (rank_ != 0 || impl_->finished) return;
  impl_->finished = true;
  impl_->courier.reset();  // nobody waits for an answer any more: the render's worker threads have ended
  impl_->rank_lost = !lost_ranks().empty();
  // Every rank, lost ones too (a lost rank that is gone never takes it: it is given up after a second); its
  // byte says whether a rank was lost, and so whether to skip MPI_Finalize.
  for (int r = 1; r < size_; ++r) {
    try {
      send_bytes(r, kTagQuit, Bytes{uint8_t(impl_->rank_lost)}, after(1.0));
    } catch (const std::exception&) {
    }
  }
}

int RankJob::serve(const std::string& selector, const Faults& faults) {
  const std::string who = "rank " + std::to_string(rank_) + " (" + host_name() + ")";
  try {
    RankHello hello;
    hello.host = host_name();
    std::vector<DeviceInfo> devices;
    try {
      devices = select_devices(selector);
      for (const DeviceInfo& d : devices) hello.devices.push_back(rank_device(d));
    } catch (const std::exception& e) {
      hello.error = e.what();
    }
    send_bytes(0, kTagHello, encode_hello(hello));
    std::shared_ptr<const DeviceScene> scene;
    std::string scene_error = "none was sent";
    std::atomic<int64_t> units_answered{0};
    std::map<uint32_t, std::unique_ptr<DeviceServer>> servers;
    for (;;) {
      int arrived = 0;
      MPI_Status status;
      check_mpi(MPI_Iprobe(0, MPI_ANY_TAG, MPI_COMM_WORLD, &arrived, &status), "MPI_Iprobe");
      if (!arrived) {
        std::this_thread::sleep_for(kPoll);
        continue;
      }
      const int tag = status.MPI_TAG;
      std::optional<Bytes> bytes = receive_bytes(0, tag, Clock::time_point::max());
      if (tag == kTagQuit) {
        impl_->rank_lost = !bytes->empty() && (*bytes)[0] != 0;
        break;
      }
      if (tag == kTagScene) {
        try {
          scene = std::make_shared<const DeviceScene>(decode_scene(*bytes));
        } catch (const std::exception& e) {
          scene_error = e.what();
        }
        continue;
      }
      const uint32_t device = uint32_t(tag / 8 - 1);
      if (tag < 8 || device >= devices.size()) throw RankMessageError("a request with tag " + std::to_string(tag));
      auto& server = servers[device];
      if (!server) server = std::make_unique<DeviceServer>(devices[device], device, &scene, &scene_error, faults, &units_answered);
      server->push(tag % 8, std::move(*bytes));
    }
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s: %s\n", who.c_str(), e.what());
    return 1;
  }
}

#endif
