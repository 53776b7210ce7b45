#include "runtime/checkpoint.h"

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>

#include <unistd.h>

#include "runtime/atomic_file.h"
#include "runtime/hash.h"
#include "runtime/scene_buffers.h"
#include "runtime/technique.h"

namespace {

constexpr char kMagicV1[8] = {'P', 'C', 'L', 'C', 'K', 'P', 'T', '1'};
constexpr char kMagic[8] = {'P', 'C', 'L', 'C', 'K', 'P', 'T', '2'};

// Followed by the film's layer names (FilmLayout::names, names_bytes long), the film's words, then the
// checksum. Version 1 had no names and `integrator` where `technique` is, then the layers' words.
struct Header {
  char magic[8];
  uint64_t key;
  uint32_t width, height, spp, technique;
  uint32_t names_bytes, pad;
};
constexpr size_t kHeaderV1Bytes = 32;

template <class T>
uint64_t hash_vector(const std::vector<T>& v, uint64_t h) {
  return fnv1a(v.data(), v.size() * sizeof(T), h);
}

const char* technique_name_of(uint32_t id) {
  const Technique* t = technique_with_id(id);
  return t ? t->name.c_str() : "unknown";
}

}  // namespace

uint64_t render_key(const DeviceScene& scene, const RenderOptions& options) {
  // The BVH layouts are left out (the header's node count with them): which ones a scene holds depends on
  // the devices (DeviceScene::bvh_layouts), and all hold the same tree, whose leaf order prims has.
  SceneHeader header = scene.header;
  header.node_count = 0;
  uint64_t h = fnv1a(&header, sizeof header);
#define PC_HASH_ARRAY(T, name) \
  if (!is_bvh_layout_array(#name)) h = hash_vector(scene.name, h);
  PC_SCENE_ARRAYS(PC_HASH_ARRAY)
#undef PC_HASH_ARRAY
  const uint32_t settings[] = {options.spp, options.max_depth, options.seed, options.rr_depth, options.sampler};
  h = fnv1a(settings, sizeof settings, h);
  // Other techniques than `path` are in the key too (path keys are as before they existed).
  const Technique& t = technique_named(options.integrator, "integrator");
  if (t.id != PC_INTEGRATOR_PATH) h = fnv1a(&t.id, sizeof t.id, h);
  if (t.key_settings) {
    const std::vector<double> settings_of_technique = t.key_settings(options);
    h = fnv1a(settings_of_technique.data(), settings_of_technique.size() * sizeof(double), h);
  }
  return h;
}

void write_checkpoint(const std::string& path, uint64_t key, const Film& film) {
  Header header{};
  std::memcpy(header.magic, kMagic, sizeof kMagic);
  header.key = key;
  header.width = film.width;
  header.height = film.height;
  header.spp = film.spp;
  header.technique = technique_named(film.technique, "checkpoint").id;
  const std::string names = film.layout.names();
  header.names_bytes = uint32_t(names.size());
  uint64_t checksum = fnv1a(&header, sizeof header);
  checksum = fnv1a(names.data(), names.size(), checksum);
  checksum = fnv1a(film.words.data(), film.words.size() * sizeof(uint32_t), checksum);
  write_file_atomically(path, "the checkpoint", [&](const std::string& tmp) {
    errno = 0;
    std::ofstream out(tmp, std::ios::binary);
    out.write(reinterpret_cast<const char*>(&header), sizeof header);
    out.write(names.data(), std::streamsize(names.size()));
    out.write(reinterpret_cast<const char*>(film.words.data()), std::streamsize(film.words.size() * sizeof(uint32_t)));
    out.write(reinterpret_cast<const char*>(&checksum), sizeof checksum);
    out.flush();
    if (!out) throw std::runtime_error(errno ? std::strerror(errno) : "the write failed");
  });
}

Film read_checkpoint(const std::string& path, uint64_t key, uint32_t width, uint32_t height, const Technique& technique,
                     const FilmLayout& layout) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw UsageError(path + ": cannot open the checkpoint");
  std::vector<char> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const bool v1 = bytes.size() >= sizeof kMagicV1 && std::memcmp(bytes.data(), kMagicV1, sizeof kMagicV1) == 0;
  if (!v1 && (bytes.size() < sizeof(Header) || std::memcmp(bytes.data(), kMagic, sizeof kMagic) != 0))
    throw UsageError(path + ": not a pathcl checkpoint");
  const size_t header_bytes = v1 ? kHeaderV1Bytes : sizeof(Header);
  if (bytes.size() < header_bytes) throw UsageError(path + ": the checkpoint is truncated or damaged (wrong size)");
  Header header{};
  std::memcpy(&header, bytes.data(), header_bytes);
  if (header.width != width || header.height != height)
    throw UsageError(path + ": the checkpoint is for a " + std::to_string(header.width) + "x" +
                     std::to_string(header.height) + " film, this render is " + std::to_string(width) + "x" +
                     std::to_string(height));
  if (header.technique != technique.id)
    throw UsageError(path + ": the checkpoint is of the " + technique_name_of(header.technique) +
                     " integrator, this render uses " + technique.name);
  if (bytes.size() < header_bytes + header.names_bytes)
    throw UsageError(path + ": the checkpoint is truncated or damaged (wrong size)");
  // Version 1 held the technique's own layers alone.
  const std::string names = v1 ? make_film_layout(technique.layers, 0, layout.pixels).names()
                               : std::string(bytes.data() + header_bytes, header.names_bytes);
  if (names != layout.names())
    throw UsageError(path + ": the checkpoint has the film layers " + names + ", this render " + layout.names() +
                     (v1 ? " (it was written before AOVs existed: resume it without --aov)" : " (--aov must match)"));
  const size_t film_bytes = layout.total_words() * sizeof(uint32_t);
  const size_t body = header_bytes + header.names_bytes;
  if (bytes.size() != body + film_bytes + sizeof(uint64_t))
    throw UsageError(path + ": the checkpoint is truncated or damaged (wrong size)");
  uint64_t stored;
  std::memcpy(&stored, bytes.data() + bytes.size() - sizeof stored, sizeof stored);
  if (fnv1a(bytes.data(), bytes.size() - sizeof stored) != stored)
    throw UsageError(path + ": the checkpoint is damaged (checksum mismatch)");
  if (header.key != key)
    throw UsageError(path + ": the checkpoint belongs to another scene or other settings (spp, max_depth, seed, "
                     "sampler must match)");
  Film film = make_film(width, height, technique.name, layout);
  film.spp = header.spp;
  std::memcpy(film.words.data(), bytes.data() + body, film_bytes);
  if (technique.units == UnitKind::pixels && layout.find("radiance") >= 0) {
    Film check = film;  // the accumulators' counts must agree with the header's spp
    develop_radiance(check);
    if (check.spp != header.spp) throw UsageError(path + ": the checkpoint is inconsistent (sample counts differ)");
  }
  return film;
}

Film read_checkpoint(const std::string& path, const DeviceScene& scene, const RenderOptions& options) {
  const Technique& technique = technique_named(options.integrator, "integrator");
  const uint32_t width = scene.header.width, height = scene.header.height;
  return read_checkpoint(path, options.checkpoint_key, width, height, technique,
                         make_film_layout(technique_layers(technique, options.max_depth), options.aovs, width * height));
}
