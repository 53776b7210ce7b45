// The messages between the ranks of an MPI render (runtime/ranks.h) as bytes, without MPI: what a rank's
// devices are, the device scene, a worker's settings, a work unit and its input, and what the worker gives
// back. Every message ends with a checksum of its bytes, and a decoder reads exactly the bytes it
// was given: a message that is short, long or damaged is refused (RankMessageError), never trusted.
#pragma once
#include <cstdint>
#include <cstring>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

#include "runtime/device.h"
#include "runtime/light_transport.h"
#include "runtime/unit_worker.h"
#include "scene/device_scene.h"

struct RankMessageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// Plain values and vectors of them, appended in order.
class ByteWriter {
 public:
  template <class T>
  void pod(const T& v) {
    static_assert(std::is_trivially_copyable_v<T>);
    const auto* p = reinterpret_cast<const uint8_t*>(&v);
    bytes_.insert(bytes_.end(), p, p + sizeof(T));
  }
  template <class T>
  void vec(const std::vector<T>& v) {
    static_assert(std::is_trivially_copyable_v<T>);
    pod(uint64_t(v.size()));
    const auto* p = reinterpret_cast<const uint8_t*>(v.data());
    bytes_.insert(bytes_.end(), p, p + v.size() * sizeof(T));
  }
  void str(const std::string& s) {
    pod(uint64_t(s.size()));
    bytes_.insert(bytes_.end(), s.begin(), s.end());
  }
  // The bytes with their checksum appended.
  std::vector<uint8_t> finish();

 private:
  std::vector<uint8_t> bytes_;
};

// Reads what ByteWriter wrote, after checking the checksum; `what` names the message in errors.
class ByteReader {
 public:
  ByteReader(const std::vector<uint8_t>& bytes, const std::string& what);
  template <class T>
  T pod() {
    T v;
    std::memcpy(&v, take(sizeof(T)), sizeof(T));
    return v;
  }
  template <class T>
  std::vector<T> vec() {
    uint64_t n = pod<uint64_t>();
    if (n > uint64_t(end_ - at_) / sizeof(T)) fail("an array longer than the message");
    std::vector<T> v(n);
    if (n) std::memcpy(v.data(), take(n * sizeof(T)), n * sizeof(T));
    return v;
  }
  std::string str();
  // Every byte was read.
  void done() const;

 private:
  const uint8_t* take(size_t n);
  [[noreturn]] void fail(const std::string& why) const;
  const uint8_t *at_, *end_;
  std::string what_;
};

// A device of a rank, as the render loop sees it there.
struct RankDevice {
  std::string name, platform;
  bool is_gpu = false, is_cpu = false;
  uint32_t compute_units = 0;
  uint64_t global_memory = 0;
};
// What a rank says when it starts: its host, its devices, or why it has none.
struct RankHello {
  std::string host;
  std::vector<RankDevice> devices;
  std::string error;  // non-empty: its devices could not be chosen (its --device), with the message
};
std::vector<uint8_t> encode_hello(const RankHello& hello);
RankHello decode_hello(const std::vector<uint8_t>& bytes);
RankDevice rank_device(const DeviceInfo& info);
DeviceInfo device_info(const RankDevice& device);  // no OpenCL handles: the report's and the schedule's fields

// The device scene, whole (every array and the figures the reports show).
std::vector<uint8_t> encode_scene(const DeviceScene& scene);
DeviceScene decode_scene(const std::vector<uint8_t>& bytes);

// A worker's prepare(): the header and its settings, the technique by name and the light set-up by value.
struct WorkerSetupMessage {
  SceneHeader header{};
  WorkerSettings settings;      // settings.technique and settings.light point into this message's owner
  std::string technique;        // Technique::name
  bool has_light = false;
  LightTransportSetup light;
};
std::vector<uint8_t> encode_setup(const SceneHeader& header, const WorkerSettings& settings);
// settings.technique is looked up by name; settings.light points at `out.light` (keep `out` alive).
void decode_setup(const std::vector<uint8_t>& bytes, WorkerSetupMessage& out);

// probe(count, spp)'s request.
std::vector<uint8_t> encode_probe_request(uint32_t count, uint32_t spp);
void decode_probe_request(const std::vector<uint8_t>& bytes, uint32_t* count, uint32_t* spp);

std::vector<uint8_t> encode_unit(const WorkUnit& unit, const std::vector<uint32_t>* input);
WorkUnit decode_unit(const std::vector<uint8_t>& bytes, std::vector<uint32_t>& input);

// A worker's answers: each is ok with its value, or the error the worker threw (and whether it was a
// UsageError).
std::vector<uint8_t> encode_error(const std::string& message, bool usage_error);
std::vector<uint8_t> encode_report(const WorkerReport& report);
std::vector<uint8_t> encode_probe(uint64_t hash);
std::vector<uint8_t> encode_output(const UnitOutput& output);
// Throws UsageError or RuntimeFailure with the worker's message (prefixed by `who`) for an error answer.
WorkerReport decode_report(const std::vector<uint8_t>& bytes, const std::string& who);
uint64_t decode_probe(const std::vector<uint8_t>& bytes, const std::string& who);
UnitOutput decode_output(const std::vector<uint8_t>& bytes, const std::string& who);
