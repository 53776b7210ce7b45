#include "runtime/checkpoint.h"

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>

#include <unistd.h>

#include "runtime/atomic_file.h"
#include "runtime/hash.h"
#include "runtime/light_transport.h"  // uses_splat_film
#include "scene/scene_description.h"  // integrator_name

namespace {

constexpr char kMagic[8] = {'P', 'C', 'L', 'C', 'K', 'P', 'T', '1'};

// Followed by the film, then the checksum: for `path`, 3 * width * height pc_float4 accumulators; for
// `light`, PC_SPLAT_WORDS * width * height uint64_t fixed-point sums (the splat film, exact integers).
// integrator (PC_INTEGRATOR_*) was a zero pad before light checkpoints: path checkpoints are unchanged.
struct Header {
  char magic[8];
  uint64_t key;
  uint32_t width, height, spp, integrator;
};

// The film's words as the file stores them: the accumulators, or the splat sums.
struct FilmBytes {
  const void* data;
  size_t size;
};
FilmBytes film_bytes(const Film& film) {
  if (!film.splats.empty()) return {film.splats.data(), film.splats.size() * sizeof(uint64_t)};
  return {film.accumulators.data(), film.accumulators.size() * sizeof(pc_float4)};
}

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
  h = fnv1a(settings, sizeof settings, h);
  // Other integrators than `path` are in the key too (path keys are as before they existed).
  if (options.integrator != PC_INTEGRATOR_PATH) h = fnv1a(&options.integrator, sizeof options.integrator, h);
  return h;
}

void write_checkpoint(const std::string& path, uint64_t key, const Film& film) {
  Header header{};
  std::memcpy(header.magic, kMagic, sizeof kMagic);
  header.key = key;
  header.width = film.width;
  header.height = film.height;
  header.spp = film.spp;
  header.integrator = film.integrator;
  const FilmBytes body = film_bytes(film);
  uint64_t checksum = fnv1a(&header, sizeof header);
  checksum = fnv1a(body.data, body.size, checksum);
  write_file_atomically(path, "the checkpoint", [&](const std::string& tmp) {
    errno = 0;
    std::ofstream out(tmp, std::ios::binary);
    out.write(reinterpret_cast<const char*>(&header), sizeof header);
    out.write(static_cast<const char*>(body.data), std::streamsize(body.size));
    out.write(reinterpret_cast<const char*>(&checksum), sizeof checksum);
    out.flush();
    if (!out) throw std::runtime_error(errno ? std::strerror(errno) : "the write failed");
  });
}

Film read_checkpoint(const std::string& path, uint64_t key, uint32_t width, uint32_t height, uint32_t integrator) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw UsageError(path + ": cannot open the checkpoint");
  std::vector<char> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  Header header;
  const bool light = uses_splat_film(integrator);
  const size_t film_size = light ? PC_SPLAT_WORDS * size_t(width) * height * sizeof(uint64_t)
                                 : 3 * size_t(width) * height * sizeof(pc_float4);
  size_t expected = sizeof header + film_size + sizeof(uint64_t);
  if (bytes.size() < sizeof header || std::memcmp(bytes.data(), kMagic, sizeof kMagic) != 0)
    throw UsageError(path + ": not a pathcl checkpoint");
  std::memcpy(&header, bytes.data(), sizeof header);
  if (header.width != width || header.height != height)
    throw UsageError(path + ": the checkpoint is for a " + std::to_string(header.width) + "x" +
                     std::to_string(header.height) + " film, this render is " + std::to_string(width) + "x" +
                     std::to_string(height));
  if (header.integrator != integrator)
    throw UsageError(path + ": the checkpoint is of the " + integrator_name(header.integrator) +
                     " integrator, this render uses " + integrator_name(integrator));
  if (bytes.size() != expected) throw UsageError(path + ": the checkpoint is truncated or damaged (wrong size)");
  uint64_t stored;
  std::memcpy(&stored, bytes.data() + bytes.size() - sizeof stored, sizeof stored);
  if (fnv1a(bytes.data(), bytes.size() - sizeof stored) != stored)
    throw UsageError(path + ": the checkpoint is damaged (checksum mismatch)");
  if (header.key != key)
    throw UsageError(path + ": the checkpoint belongs to another scene or other settings (spp, max_depth, seed, "
                     "sampler must match)");
  if (light) {
    // The splat film alone: its sums are what a resumed render adds to (the means need the render's
    // fixed-point scale, runtime/light_transport.h, and are derived when it ends).
    Film film;
    film.width = width;
    film.height = height;
    film.spp = header.spp;
    film.integrator = integrator;
    film.splats.resize(PC_SPLAT_WORDS * size_t(width) * height);
    std::memcpy(film.splats.data(), bytes.data() + sizeof header, film_size);
    return film;
  }
  std::vector<pc_float4> acc(3 * size_t(width) * height);
  std::memcpy(acc.data(), bytes.data() + sizeof header, film_size);
  Film film = film_from_accumulators(width, height, std::move(acc));
  if (film.spp != header.spp) throw UsageError(path + ": the checkpoint is inconsistent (sample counts differ)");
  return film;
}
