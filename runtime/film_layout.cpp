#include "runtime/film_layout.h"

#include "runtime/errors.h"

namespace {
const AovInfo kAovs[PC_AOV_COUNT] = {
    {"albedo", 3, "RGB", false}, {"normal", 3, "XYZ", false}, {"depth", 1, "Z", false},
    {"position", 3, "XYZ", false}, {"uv", 2, "UV", false}, {"shape_id", 1, "I", true},
    {"material_id", 1, "I", true},
};
}  // namespace

size_t FilmLayout::offset(size_t i) const {
  size_t words = 0;
  for (size_t k = 0; k < i; ++k) words += size_t(layers[k].words) * pixels;
  return words;
}

size_t FilmLayout::total_words() const { return offset(layers.size()); }

size_t FilmLayout::words_per_pixel(uint32_t kind) const {
  size_t words = 0;
  for (const FilmLayer& l : layers)
    if (l.kind == kind) words += l.words;
  return words;
}

FilmLayout::UnitPart FilmLayout::unit_part(size_t i, uint32_t pixel_begin, uint32_t pixel_count) const {
  const uint32_t kind = layers[i].kind;
  const size_t unit_pixels = kind == PC_LAYER_ORDERED ? pixel_count : pixels;
  size_t payload = 0;
  for (size_t k = 0; k < i; ++k)
    if (layers[k].kind == kind) payload += size_t(layers[k].words) * unit_pixels;
  const size_t first = kind == PC_LAYER_ORDERED ? size_t(layers[i].words) * pixel_begin : 0;
  return {offset(i) + first, payload, size_t(layers[i].words) * unit_pixels};
}

int FilmLayout::find(const std::string& name) const {
  for (size_t i = 0; i < layers.size(); ++i)
    if (layers[i].name == name) return int(i);
  return -1;
}

bool FilmLayout::operator==(const FilmLayout& o) const {
  if (pixels != o.pixels || layers.size() != o.layers.size()) return false;
  for (size_t i = 0; i < layers.size(); ++i)
    if (layers[i].name != o.layers[i].name || layers[i].kind != o.layers[i].kind || layers[i].words != o.layers[i].words)
      return false;
  return true;
}

std::string FilmLayout::names() const {
  std::string s;
  for (const FilmLayer& l : layers) s += (s.empty() ? "" : ",") + l.name;
  return s;
}

const AovInfo& aov_info(uint32_t aov) { return kAovs[aov]; }

uint32_t aov_mask_from_names(const std::string& list, const std::string& where) {
  uint32_t mask = 0;
  size_t begin = 0;
  while (begin <= list.size()) {
    size_t end = list.find(',', begin);
    if (end == std::string::npos) end = list.size();
    std::string name = list.substr(begin, end - begin);
    begin = end + 1;
    if (name.empty() && list.empty()) break;
    uint32_t a = 0;
    while (a < PC_AOV_COUNT && name != kAovs[a].name) ++a;
    if (a == PC_AOV_COUNT) {
      std::string known;
      for (const AovInfo& i : kAovs) known += std::string(known.empty() ? "" : ", ") + i.name;
      throw UsageError(where + ": unknown AOV \"" + name + "\" (expected a comma-separated list of " + known + ")");
    }
    mask |= 1u << a;
  }
  return mask;
}

std::string aov_names(uint32_t mask) {
  std::string s;
  for (uint32_t a = 0; a < PC_AOV_COUNT; ++a)
    if (mask >> a & 1u) s += std::string(s.empty() ? "" : ",") + kAovs[a].name;
  return s;
}

FilmLayout make_film_layout(const std::vector<FilmLayer>& technique_layers, uint32_t aov_mask, uint32_t pixels) {
  FilmLayout layout;
  layout.pixels = pixels;
  layout.layers = technique_layers;
  for (uint32_t a = 0; a < PC_AOV_COUNT; ++a)
    if (aov_mask >> a & 1u) layout.layers.push_back({kAovs[a].name, PC_LAYER_ORDERED, kAovs[a].words});
  return layout;
}

AovHeader aov_header(const FilmLayout& layout, const double origin[3]) {
  AovHeader h{};
  h.origin = {float(origin[0]), float(origin[1]), float(origin[2]), 0.0f};
  for (uint32_t a = 0; a < 8; ++a) h.offset[a] = PC_INVALID;
  for (uint32_t a = 0; a < PC_AOV_COUNT; ++a) {
    int i = layout.find(kAovs[a].name);
    if (i >= 0) h.offset[a] = uint32_t(layout.offset(size_t(i)));
  }
  return h;
}
