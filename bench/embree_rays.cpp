// Embree 3 ray throughput on the same triangles and ray files as `pathcl rays` (scripts/bench/peers).
//   embree_rays SCENE.obj RAYS [--threads N] [--repeat R] [--hits OUT] [--compare PATHCL_HITS] [--packet 1|8|16]
//               [--robust 0|1] [--isa NAME]
// SCENE.obj is `pathcl info --dump-obj` output: all faces in file order form one triangle geometry, so
// Embree's primID is pathcl's primitive index (scenes without spheres). Rays and hits use pathcl's
// 32- and 16-byte records (docs/scene-format.md). Traces with rtcIntersect1 (or, with --packet, rtcIntersect8
// or rtcIntersect16 on consecutive rays) on N threads that take chunks of kChunk rays in turn, R timed
// repetitions, and prints one JSON line: rays, hits, build and per-repetition times, median rays/s, and
// with --compare the fraction of rays whose primitive (or miss) agrees with pathcl's. --robust 1 sets
// RTC_SCENE_FLAG_ROBUST (conservative node tests and watertight triangle tests, as pathcl's always are).
// --isa avx2 (or sse4.2, avx, avx512) caps the instruction set Embree's code uses.
// Built by scripts/bench/peers (not part of the CMake build, which does not depend on Embree).
#include <embree3/rtcore.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

namespace {

struct Ray {  // 32 bytes, as kernels/shared/types.h RayRecord
  float org[3], tmin, dir[3], tmax;
};
struct Hit {  // 16 bytes, as HitRecord
  float t;
  uint32_t prim;
  float u, v;
};
constexpr uint32_t kMiss = 0xffffffffu;

template <class T>
std::vector<T> read_records(const std::string& path) {
  std::ifstream in(path, std::ios::binary | std::ios::ate);
  if (!in) throw std::runtime_error(path + ": cannot open");
  std::streamsize size = in.tellg();
  if (size % sizeof(T)) throw std::runtime_error(path + ": size is not a multiple of the record size");
  std::vector<T> out(size / sizeof(T));
  in.seekg(0);
  in.read(reinterpret_cast<char*>(out.data()), size);
  return out;
}

void read_obj(const std::string& path, std::vector<float>& v, std::vector<uint32_t>& f) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error(path + ": cannot open");
  std::string line;
  while (std::getline(in, line)) {
    if (line.size() < 2 || line[1] != ' ') continue;
    std::istringstream s(line.substr(2));
    if (line[0] == 'v') {
      float x, y, z;
      s >> x >> y >> z;
      v.insert(v.end(), {x, y, z});
    } else if (line[0] == 'f') {
      uint32_t a, b, c;
      s >> a >> b >> c;
      f.insert(f.end(), {a - 1, b - 1, c - 1});
    }
  }
}

double seconds_since(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
}

void trace(RTCScene scene, const std::vector<Ray>& rays, std::vector<Hit>& hits, size_t begin, size_t end) {
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  for (size_t i = begin; i < end; ++i) {
    const Ray& r = rays[i];
    RTCRayHit rh{};
    rh.ray.org_x = r.org[0], rh.ray.org_y = r.org[1], rh.ray.org_z = r.org[2], rh.ray.tnear = r.tmin;
    rh.ray.dir_x = r.dir[0], rh.ray.dir_y = r.dir[1], rh.ray.dir_z = r.dir[2], rh.ray.tfar = r.tmax;
    rh.ray.mask = 0xffffffffu;
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(scene, &context, &rh);
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID)
      hits[i] = {INFINITY, kMiss, 0, 0};
    else
      hits[i] = {rh.ray.tfar, rh.hit.primID, rh.hit.u, rh.hit.v};
  }
}

// The same with rtcIntersect8 or rtcIntersect16 (RTCRayHitN: 8 or 16 rays by coordinate), consecutive rays
// as one packet, as a renderer that traces its SIMD lanes' rays together would (Mitsuba's llvm variants).
template <int N, typename RayHitN, typename Intersect>
void trace_packets(RTCScene scene, const std::vector<Ray>& rays, std::vector<Hit>& hits, size_t begin, size_t end,
                   Intersect intersect) {
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  for (size_t first = begin; first < end; first += N) {
    alignas(64) RayHitN rh{};
    alignas(64) int valid[N];
    for (int j = 0; j < N; ++j) {
      size_t i = std::min(first + j, end - 1);
      const Ray& r = rays[i];
      valid[j] = first + j < end ? -1 : 0;
      rh.ray.org_x[j] = r.org[0], rh.ray.org_y[j] = r.org[1], rh.ray.org_z[j] = r.org[2], rh.ray.tnear[j] = r.tmin;
      rh.ray.dir_x[j] = r.dir[0], rh.ray.dir_y[j] = r.dir[1], rh.ray.dir_z[j] = r.dir[2], rh.ray.tfar[j] = r.tmax;
      rh.ray.mask[j] = 0xffffffffu;
      rh.hit.geomID[j] = RTC_INVALID_GEOMETRY_ID;
    }
    intersect(valid, scene, &context, &rh);
    for (int j = 0; j < N && first + j < end; ++j) {
      if (rh.hit.geomID[j] == RTC_INVALID_GEOMETRY_ID)
        hits[first + j] = {INFINITY, kMiss, 0, 0};
      else
        hits[first + j] = {rh.ray.tfar[j], rh.hit.primID[j], rh.hit.u[j], rh.hit.v[j]};
    }
  }
}

// Rays a thread takes at a time. Dynamic, as PoCL hands out work-groups: two static halves left one thread
// idle at the end, which cost Embree 3.8 % on the terrain's bounce rays with 2 threads (10 rounds,
// docs/benchmarks-notes.md); 64 to 4096 rays all measured within 2 % of each other. A multiple of 16, so
// that packets are the same consecutive rays with any thread count.
constexpr size_t kChunk = 256;

void trace_with(int packet, RTCScene scene, const std::vector<Ray>& rays, std::vector<Hit>& hits, size_t begin,
                size_t end) {
  if (packet == 16)
    trace_packets<16, RTCRayHit16>(scene, rays, hits, begin, end, [](const int* v, RTCScene s, RTCIntersectContext* c,
                                                                     RTCRayHit16* rh) { rtcIntersect16(v, s, c, rh); });
  else if (packet == 8)
    trace_packets<8, RTCRayHit8>(scene, rays, hits, begin, end, [](const int* v, RTCScene s, RTCIntersectContext* c,
                                                                   RTCRayHit8* rh) { rtcIntersect8(v, s, c, rh); });
  else
    trace(scene, rays, hits, begin, end);
}

}  // namespace

int main(int argc, char** argv) {
  try {
    if (argc < 3) throw std::runtime_error("usage: embree_rays SCENE.obj RAYS [--threads N] [--repeat R] [--hits OUT] "
                                           "[--compare PATHCL_HITS] [--packet 1|8|16] [--robust 0|1] [--isa NAME]");
    std::string obj = argv[1], ray_path = argv[2], hits_out, compare, isa;
    int threads = 1, repeat = 5, packet = 1, robust = 0;
    for (int i = 3; i + 1 < argc; i += 2) {
      std::string k = argv[i];
      if (k == "--threads") threads = std::atoi(argv[i + 1]);
      else if (k == "--repeat") repeat = std::atoi(argv[i + 1]);
      else if (k == "--hits") hits_out = argv[i + 1];
      else if (k == "--compare") compare = argv[i + 1];
      else if (k == "--packet") packet = std::atoi(argv[i + 1]);
      else if (k == "--robust") robust = std::atoi(argv[i + 1]);
      else if (k == "--isa") isa = argv[i + 1];
      else throw std::runtime_error("unknown option " + k);
    }
    if (packet != 1 && packet != 8 && packet != 16) throw std::runtime_error("--packet: 1, 8 or 16 rays");
    std::vector<float> verts;
    std::vector<uint32_t> faces;
    read_obj(obj, verts, faces);
    std::vector<Ray> rays = read_records<Ray>(ray_path);

    auto t0 = std::chrono::steady_clock::now();
    // isa=avx2 (Embree's device configuration) keeps an AVX-512 machine to Embree's AVX2 code.
    std::string config = "threads=" + std::to_string(threads) + (isa.empty() ? "" : ",isa=" + isa);
    RTCDevice device = rtcNewDevice(config.c_str());
    if (!device) throw std::runtime_error("rtcNewDevice failed");
    RTCScene scene = rtcNewScene(device);
    if (robust) rtcSetSceneFlags(scene, RTC_SCENE_FLAG_ROBUST);
    RTCGeometry geom = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
    float* vb = static_cast<float*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                            3 * sizeof(float), verts.size() / 3));
    std::memcpy(vb, verts.data(), verts.size() * sizeof(float));
    uint32_t* ib = static_cast<uint32_t*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                                  3 * sizeof(uint32_t), faces.size() / 3));
    std::memcpy(ib, faces.data(), faces.size() * sizeof(uint32_t));
    rtcCommitGeometry(geom);
    rtcAttachGeometry(scene, geom);
    rtcReleaseGeometry(geom);
    rtcCommitScene(scene);
    double build_ms = seconds_since(t0) * 1e3;

    std::vector<Hit> hits(rays.size());
    std::vector<double> ms;
    for (int r = 0; r < repeat; ++r) {
      auto t = std::chrono::steady_clock::now();
      std::vector<std::thread> pool;
      std::atomic<size_t> next{0};
      for (int k = 0; k < threads; ++k)
        pool.emplace_back([&] {
          for (size_t b; (b = next.fetch_add(kChunk)) < rays.size();)
            trace_with(packet, scene, rays, hits, b, std::min(rays.size(), b + kChunk));
        });
      for (auto& p : pool) p.join();
      ms.push_back(seconds_since(t) * 1e3);
    }
    std::vector<double> sorted = ms;
    std::sort(sorted.begin(), sorted.end());
    double median = sorted[sorted.size() / 2];
    size_t hit_count = std::count_if(hits.begin(), hits.end(), [](const Hit& h) { return h.prim != kMiss; });
    std::printf("{\"triangles\": %zu, \"rays\": %zu, \"hits\": %zu, \"threads\": %d, \"build_ms\": %.3f, \"ms\": [",
                faces.size() / 3, rays.size(), hit_count, threads, build_ms);
    for (size_t i = 0; i < ms.size(); ++i) std::printf("%s%.3f", i ? ", " : "", ms[i]);
    std::printf("], \"ms_median\": %.3f, \"rays_per_second\": %.1f", median, rays.size() / median * 1e3);
    if (!compare.empty()) {
      std::vector<Hit> other = read_records<Hit>(compare);
      if (other.size() != hits.size()) throw std::runtime_error(compare + ": not one hit record per ray");
      size_t same = 0, t_close = 0, both_hit = 0;
      for (size_t i = 0; i < hits.size(); ++i) {
        same += hits[i].prim == other[i].prim;
        if (hits[i].prim != kMiss && other[i].prim != kMiss) {
          ++both_hit;
          t_close += std::abs(hits[i].t - other[i].t) <= 1e-4f * std::max(1.0f, std::abs(other[i].t));
        }
      }
      std::printf(", \"same_primitive_fraction\": %.8f, \"t_within_1e-4_fraction\": %.8f",
                  double(same) / hits.size(), both_hit ? double(t_close) / both_hit : 1.0);
    }
    std::printf("}\n");
    if (!hits_out.empty()) {
      std::ofstream out(hits_out, std::ios::binary);
      out.write(reinterpret_cast<const char*>(hits.data()), std::streamsize(hits.size() * sizeof(Hit)));
    }
    rtcReleaseScene(scene);
    rtcReleaseDevice(device);
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 2;
  }
}
