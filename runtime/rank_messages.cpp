#include "runtime/rank_messages.h"

#include "runtime/errors.h"
#include "runtime/technique.h"

namespace {

// A message's checksum: four independent multiply-rotate lanes over 8-byte words (about 8 bytes a cycle;
// FNV-1a's one byte a step took 2 ms of every 1.6 MB unit result at each end), then the tail bytes. Finds
// damage, not attacks.
uint64_t message_checksum(const uint8_t* p, size_t n) {
  constexpr uint64_t k = 0x9e3779b97f4a7c15ull;
  uint64_t lane[4] = {k, k ^ 1, k ^ 2, k ^ 3};
  auto mix = [&](uint64_t h, uint64_t w) {
    h ^= w;
    h *= k;
    return h << 31 | h >> 33;
  };
  size_t i = 0;
  for (; i + 32 <= n; i += 32)
    for (int l = 0; l < 4; ++l) {
      uint64_t w;
      std::memcpy(&w, p + i + 8 * l, 8);
      lane[l] = mix(lane[l], w);
    }
  uint64_t h = mix(mix(mix(mix(uint64_t(n), lane[0]), lane[1]), lane[2]), lane[3]);
  for (; i < n; ++i) h = mix(h, p[i]);
  return h ^ h >> 29;
}

enum : uint8_t { kAnswerOk = 1, kAnswerError = 2, kAnswerUsageError = 3 };

ByteWriter ok_answer() {
  ByteWriter w;
  w.pod(uint8_t(kAnswerOk));
  return w;
}

// An answer's reader past its status; an error answer is thrown as the worker threw it.
ByteReader answer(const std::vector<uint8_t>& bytes, const std::string& who, const char* what) {
  ByteReader r(bytes, std::string("the answer to ") + what + " from " + who);
  uint8_t status = r.pod<uint8_t>();
  if (status == kAnswerOk) return r;
  std::string message = r.str();
  r.done();
  if (status == kAnswerUsageError) throw UsageError(who + ": " + message);
  if (status == kAnswerError) throw RuntimeFailure(who + ": " + message);
  throw RankMessageError("the answer to " + std::string(what) + " from " + who + " has an unknown status " +
                         std::to_string(status));
}

}  // namespace

std::vector<uint8_t> ByteWriter::finish() {
  std::vector<uint8_t> out = std::move(bytes_);
  uint64_t h = message_checksum(out.data(), out.size());
  const auto* p = reinterpret_cast<const uint8_t*>(&h);
  out.insert(out.end(), p, p + sizeof h);
  return out;
}

ByteReader::ByteReader(const std::vector<uint8_t>& bytes, const std::string& what) : what_(what) {
  if (bytes.size() < sizeof(uint64_t)) fail("shorter than its checksum (" + std::to_string(bytes.size()) + " bytes)");
  at_ = bytes.data();
  end_ = bytes.data() + bytes.size() - sizeof(uint64_t);
  uint64_t h;
  std::memcpy(&h, end_, sizeof h);
  if (h != message_checksum(at_, end_ - at_)) fail("its checksum does not match its " + std::to_string(bytes.size()) + " bytes");
}

const uint8_t* ByteReader::take(size_t n) {
  if (n > size_t(end_ - at_)) fail("it ends early");
  const uint8_t* p = at_;
  at_ += n;
  return p;
}

std::string ByteReader::str() {
  uint64_t n = pod<uint64_t>();
  if (n > uint64_t(end_ - at_)) fail("a string longer than the message");
  const char* p = reinterpret_cast<const char*>(take(n));
  return std::string(p, p + n);
}

void ByteReader::done() const {
  if (at_ != end_) fail(std::to_string(end_ - at_) + " bytes are left over");
}

void ByteReader::fail(const std::string& why) const { throw RankMessageError(what_ + " is malformed: " + why); }

RankDevice rank_device(const DeviceInfo& info) {
  return {info.name, info.platform_name, info.is_gpu, info.is_cpu, uint32_t(info.compute_units), info.global_memory};
}

DeviceInfo device_info(const RankDevice& d) {
  DeviceInfo info;
  info.name = d.name;
  info.platform_name = d.platform;
  info.is_gpu = d.is_gpu;
  info.is_cpu = d.is_cpu;
  info.compute_units = d.compute_units;
  info.global_memory = d.global_memory;
  return info;
}

std::vector<uint8_t> encode_hello(const RankHello& hello) {
  ByteWriter w;
  w.str(hello.host);
  w.str(hello.error);
  w.pod(uint64_t(hello.devices.size()));
  for (const RankDevice& d : hello.devices) {
    w.str(d.name);
    w.str(d.platform);
    w.pod(uint8_t(d.is_gpu));
    w.pod(uint8_t(d.is_cpu));
    w.pod(d.compute_units);
    w.pod(d.global_memory);
  }
  return w.finish();
}

RankHello decode_hello(const std::vector<uint8_t>& bytes) {
  ByteReader r(bytes, "a rank's list of devices");
  RankHello hello;
  hello.host = r.str();
  hello.error = r.str();
  uint64_t n = r.pod<uint64_t>();
  if (n > 4096) throw RankMessageError("a rank's list of devices is malformed: " + std::to_string(n) + " devices");
  for (uint64_t i = 0; i < n; ++i) {
    RankDevice d;
    d.name = r.str();
    d.platform = r.str();
    d.is_gpu = r.pod<uint8_t>() != 0;
    d.is_cpu = r.pod<uint8_t>() != 0;
    d.compute_units = r.pod<uint32_t>();
    d.global_memory = r.pod<uint64_t>();
    hello.devices.push_back(d);
  }
  r.done();
  return hello;
}

// The device scene's fields in one order for both directions (F: the writer's or the reader's visit).
template <class Scene, class Pod, class Vec>
void visit_scene(Scene& s, Pod&& pod, Vec&& vec) {
  pod(s.header);
  pod(s.origin);
  pod(s.view_distance);
#define PC_VISIT_ARRAY(T, name) vec(s.name);
  PC_SCENE_ARRAYS(PC_VISIT_ARRAY)
#undef PC_VISIT_ARRAY
  vec(s.leaf_slot);
  vec(s.prim_shapes);
  vec(s.instance_shapes);
  pod(s.features);
  pod(s.triangle_count);
  pod(s.sphere_count);
  pod(s.instance_count);
  pod(s.instanced_triangle_count);
  pod(s.skipped_zero_area_emitters);
  pod(s.bvh);
  pod(s.bvh_layouts);
  pod(s.wide_depth);
  pod(s.wide8_depth);
  pod(s.wide8_nodes);
  pod(s.wide16_depth);
  pod(s.wide16_nodes);
}

std::vector<uint8_t> encode_scene(const DeviceScene& scene) {
  ByteWriter w;
  visit_scene(scene, [&](const auto& v) { w.pod(v); }, [&](const auto& v) { w.vec(v); });
  return w.finish();
}

DeviceScene decode_scene(const std::vector<uint8_t>& bytes) {
  ByteReader r(bytes, "the device scene");
  DeviceScene scene;
  visit_scene(scene, [&](auto& v) { v = r.pod<std::decay_t<decltype(v)>>(); },
              [&](auto& v) { v = r.vec<typename std::decay_t<decltype(v)>::value_type>(); });
  r.done();
  return scene;
}

std::vector<uint8_t> encode_setup(const SceneHeader& header, const WorkerSettings& s) {
  ByteWriter w;
  w.pod(header);
  w.str(s.technique->name);
  w.pod(uint64_t(s.layout.layers.size()));
  for (const FilmLayer& l : s.layout.layers) {
    w.str(l.name);
    w.pod(l.kind);
    w.pod(l.words);
  }
  w.pod(s.layout.pixels);
  w.pod(s.aov);
  w.str(s.build_options);
  w.pod(uint64_t(s.work_group));
  w.pod(s.fault);
  w.pod(s.lanes);
  w.pod(s.max_depth);
  w.pod(uint8_t(s.splat_pairs));
  w.pod(uint8_t(s.light != nullptr));
  if (s.light) {
    w.pod(s.light->header);
    w.vec(s.light->emission_cdf);
    w.vec(s.light->power);
  }
  return w.finish();
}

void decode_setup(const std::vector<uint8_t>& bytes, WorkerSetupMessage& out) {
  ByteReader r(bytes, "a worker's settings");
  out.header = r.pod<SceneHeader>();
  out.technique = r.str();
  WorkerSettings& s = out.settings;
  s.technique = &technique_named(out.technique, "a worker's settings");
  uint64_t layers = r.pod<uint64_t>();
  if (layers > 64) throw RankMessageError("a worker's settings are malformed: " + std::to_string(layers) + " film layers");
  s.layout.layers.clear();
  for (uint64_t i = 0; i < layers; ++i) {
    FilmLayer l;
    l.name = r.str();
    l.kind = r.pod<uint32_t>();
    l.words = r.pod<uint32_t>();
    s.layout.layers.push_back(l);
  }
  s.layout.pixels = r.pod<uint32_t>();
  s.aov = r.pod<AovHeader>();
  s.build_options = r.str();
  s.work_group = size_t(r.pod<uint64_t>());
  s.fault = r.pod<DeviceFault>();
  s.lanes = r.pod<uint32_t>();
  s.max_depth = r.pod<uint32_t>();
  s.splat_pairs = r.pod<uint8_t>() != 0;
  out.has_light = r.pod<uint8_t>() != 0;
  if (out.has_light) {
    out.light.header = r.pod<LightTransportHeader>();
    out.light.emission_cdf = r.vec<float>();
    out.light.power = r.vec<double>();
  }
  s.light = out.has_light ? &out.light : nullptr;
  r.done();
}

std::vector<uint8_t> encode_probe_request(uint32_t count, uint32_t spp) {
  ByteWriter w;
  w.pod(count);
  w.pod(spp);
  return w.finish();
}

void decode_probe_request(const std::vector<uint8_t>& bytes, uint32_t* count, uint32_t* spp) {
  ByteReader r(bytes, "a probe request");
  *count = r.pod<uint32_t>();
  *spp = r.pod<uint32_t>();
  r.done();
}

std::vector<uint8_t> encode_unit(const WorkUnit& unit, const std::vector<uint32_t>* input) {
  ByteWriter w;
  w.pod(unit);
  w.vec(input ? *input : std::vector<uint32_t>{});
  return w.finish();
}

WorkUnit decode_unit(const std::vector<uint8_t>& bytes, std::vector<uint32_t>& input) {
  ByteReader r(bytes, "a work unit");
  WorkUnit unit = r.pod<WorkUnit>();
  input = r.vec<uint32_t>();
  r.done();
  return unit;
}

std::vector<uint8_t> encode_error(const std::string& message, bool usage_error) {
  ByteWriter w;
  w.pod(uint8_t(usage_error ? kAnswerUsageError : kAnswerError));
  w.str(message);
  return w.finish();
}

std::vector<uint8_t> encode_report(const WorkerReport& report) {
  ByteWriter w = ok_answer();
  w.pod(report.kernel_build_ms);
  w.pod(uint8_t(report.kernel_from_cache));
  w.str(report.kernel_options);
  w.pod(report.kernel_private_bytes);
  w.pod(report.lanes);
  w.pod(report.unit_items);
  w.pod(uint64_t(report.buffers.size()));
  for (const auto& [name, bytes] : report.buffers) {
    w.str(name);
    w.pod(bytes);
  }
  return w.finish();
}

WorkerReport decode_report(const std::vector<uint8_t>& bytes, const std::string& who) {
  ByteReader r = answer(bytes, who, "prepare");
  WorkerReport report;
  report.kernel_build_ms = r.pod<double>();
  report.kernel_from_cache = r.pod<uint8_t>() != 0;
  report.kernel_options = r.str();
  report.kernel_private_bytes = r.pod<uint64_t>();
  report.lanes = r.pod<uint32_t>();
  report.unit_items = r.pod<uint32_t>();
  uint64_t n = r.pod<uint64_t>();
  for (uint64_t i = 0; i < n; ++i) {
    std::string name = r.str();
    report.buffers[name] = r.pod<uint64_t>();
  }
  r.done();
  return report;
}

std::vector<uint8_t> encode_probe(uint64_t hash) {
  ByteWriter w = ok_answer();
  w.pod(hash);
  return w.finish();
}

uint64_t decode_probe(const std::vector<uint8_t>& bytes, const std::string& who) {
  ByteReader r = answer(bytes, who, "the probe");
  uint64_t hash = r.pod<uint64_t>();
  r.done();
  return hash;
}

std::vector<uint8_t> encode_output(const UnitOutput& o) {
  ByteWriter w = ok_answer();
  w.pod(o.stats);
  w.pod(o.splat_overflows);
  w.pod(o.light_vertices);
  w.pod(o.seconds);
  w.pod(o.kernel_ms);
  w.pod(uint64_t(o.phases.size()));
  for (const PhaseTime& p : o.phases) {
    w.str(p.name);
    w.pod(p.ms);
  }
  w.vec(o.ordered);
  w.vec(o.commutative);
  return w.finish();
}

UnitOutput decode_output(const std::vector<uint8_t>& bytes, const std::string& who) {
  ByteReader r = answer(bytes, who, "a work unit");
  UnitOutput o;
  o.stats = r.pod<UnitStats>();
  o.splat_overflows = r.pod<uint64_t>();
  o.light_vertices = r.pod<uint64_t>();
  o.seconds = r.pod<double>();
  o.kernel_ms = r.pod<double>();
  uint64_t n = r.pod<uint64_t>();
  if (n > 64) throw RankMessageError("the answer to a work unit from " + who + " is malformed: " + std::to_string(n) + " phases");
  for (uint64_t i = 0; i < n; ++i) {
    PhaseTime p;
    p.name = r.str();
    p.ms = r.pod<double>();
    o.phases.push_back(p);
  }
  o.ordered = r.vec<uint32_t>();
  o.commutative = r.vec<uint32_t>();
  r.done();
  return o;
}
