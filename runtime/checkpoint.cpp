#include "runtime/checkpoint.h"

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>

#include <unistd.h>

#include "runtime/atomic_file.h"
#include "runtime/hash.h"

namespace {

constexpr char kMagic[8] = {'P', 'C', 'L', 'C', 'K', 'P', 'T', '1'};

struct Header {  // followed by 3 * width * height pc_float4 accumulators, then the checksum
  char magic[8];
  uint64_t key;
  uint32_t width, height, spp, pad;
};

template <class T>
uint64_t hash_vector(const std::vector<T>& v, uint64_t h) {
  return fnv1a(v.data(), v.size() * sizeof(T), h);
}

}  // namespace

uint64_t render_key(const DeviceScene& scene, const RenderOptions& options) {
  uint64_t h = fnv1a(&scene.header, sizeof scene.header);
#define PC_HASH_ARRAY(T, name) h = hash_vector(scene.name, h);
  PC_SCENE_ARRAYS(PC_HASH_ARRAY)
#undef PC_HASH_ARRAY
  const uint32_t settings[] = {options.spp, options.max_depth, options.seed, options.rr_depth, options.sampler};
  return fnv1a(settings, sizeof settings, h);
}

void write_checkpoint(const std::string& path, uint64_t key, const Film& film) {
  Header header{};
  std::memcpy(header.magic, kMagic, sizeof kMagic);
  header.key = key;
  header.width = film.width;
  header.height = film.height;
  header.spp = film.spp;
  uint64_t checksum = fnv1a(&header, sizeof header);
  checksum = hash_vector(film.accumulators, checksum);
  write_file_atomically(path, "the checkpoint", [&](const std::string& tmp) {
    errno = 0;
    std::ofstream out(tmp, std::ios::binary);
    out.write(reinterpret_cast<const char*>(&header), sizeof header);
    out.write(reinterpret_cast<const char*>(film.accumulators.data()),
              std::streamsize(film.accumulators.size() * sizeof(pc_float4)));
    out.write(reinterpret_cast<const char*>(&checksum), sizeof checksum);
    out.flush();
    if (!out) throw std::runtime_error(errno ? std::strerror(errno) : "the write failed");
  });
}

Film read_checkpoint(const std::string& path, uint64_t key, uint32_t width, uint32_t height) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw UsageError(path + ": cannot open the checkpoint");
  std::vector<char> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  Header header;
  size_t expected = sizeof header + 3 * size_t(width) * height * sizeof(pc_float4) + sizeof(uint64_t);
  if (bytes.size() < sizeof header || std::memcmp(bytes.data(), kMagic, sizeof kMagic) != 0)
    throw UsageError(path + ": not a pathcl checkpoint");
  std::memcpy(&header, bytes.data(), sizeof header);
  if (header.width != width || header.height != height)
    throw UsageError(path + ": the checkpoint is for a " + std::to_string(header.width) + "x" +
                     std::to_string(header.height) + " film, this render is " + std::to_string(width) + "x" +
                     std::to_string(height));
  if (bytes.size() != expected) throw UsageError(path + ": the checkpoint is truncated or damaged (wrong size)");
  uint64_t stored;
  std::memcpy(&stored, bytes.data() + bytes.size() - sizeof stored, sizeof stored);
  if (fnv1a(bytes.data(), bytes.size() - sizeof stored) != stored)
    throw UsageError(path + ": the checkpoint is damaged (checksum mismatch)");
  if (header.key != key)
    throw UsageError(path + ": the checkpoint belongs to another scene or other settings (spp, max_depth, seed, "
                     "sampler must match)");
  std::vector<pc_float4> acc(3 * size_t(width) * height);
  std::memcpy(acc.data(), bytes.data() + sizeof header, acc.size() * sizeof(pc_float4));
  Film film = film_from_accumulators(width, height, std::move(acc));
  if (film.spp != header.spp) throw UsageError(path + ": the checkpoint is inconsistent (sample counts differ)");
  return film;
}
