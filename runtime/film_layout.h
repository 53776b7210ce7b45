// The film as named layers (kernels/shared/film_types.h): which layers a render's film has, where each
// plane lies in the film's words, and how a work unit's part of each is carried and committed. One
// description for the film buffer on every device, the host's film, checkpoints and the EXR writer.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "kernels/shared/types.h"
#include "kernels/shared/film_types.h"

struct FilmLayer {
  std::string name;   // "radiance", "splats", or an AOV's name ("albedo", "normal", ...)
  uint32_t kind = PC_LAYER_ORDERED;  // PC_LAYER_ORDERED or PC_LAYER_COMMUTATIVE
  uint32_t words = 0;  // 32-bit words per pixel (a commutative layer's are 64-bit sums, two words each)
};

struct FilmLayout {
  std::vector<FilmLayer> layers;  // the technique's own first, then the AOVs
  uint32_t pixels = 0;

  // Word offset of layer i's plane (layer after layer, each `words * pixels` long).
  size_t offset(size_t i) const;
  size_t total_words() const;          // of the whole film
  size_t words_per_pixel(uint32_t kind) const;  // summed over the layers of one kind
  int find(const std::string& name) const;      // the layer's index, -1 if absent
  bool operator==(const FilmLayout& o) const;
  std::string names() const;  // "radiance,albedo,normal": what checkpoints record and messages show

  // Layer i's part of a work unit of pixel_count pixels from pixel_begin: `words` of the film from
  // film_offset, carried in the unit's payload (UnitOutput) from payload_offset. An ordered layer's part is
  // its words of the unit's pixels, in UnitOutput::ordered after the earlier ordered layers' parts; a
  // commutative layer's is its whole plane, in UnitOutput::commutative after the earlier commutative planes.
  struct UnitPart {
    size_t film_offset, payload_offset, words;
  };
  UnitPart unit_part(size_t i, uint32_t pixel_begin, uint32_t pixel_count) const;
};

// f(part) for the unit part of each layer of `kind` (PC_LAYER_ORDERED or PC_LAYER_COMMUTATIVE), in order.
template <class F>
void for_each_unit_part(const FilmLayout& layout, uint32_t kind, uint32_t pixel_begin, uint32_t pixel_count, F&& f) {
  for (size_t i = 0; i < layout.layers.size(); ++i)
    if (layout.layers[i].kind == kind) f(layout.unit_part(i, pixel_begin, pixel_count));
}

// AOVs (`--aov`, render.aovs), by PC_AOV_* index.
struct AovInfo {
  const char* name;       // "albedo": as --aov takes it, and the EXR layer's name
  uint32_t words;         // per pixel
  const char* channels;   // the EXR channels of the layer, one letter each: "RGB", "XYZ", "Z", "UV", "I" (an id)
  bool id;                // an integer id of one sample (EXR UINT), not an average
};
const AovInfo& aov_info(uint32_t aov);
// "albedo,normal" -> a mask of 1 << PC_AOV_*; UsageError naming `where` and the unknown name.
uint32_t aov_mask_from_names(const std::string& list, const std::string& where);
std::string aov_names(uint32_t mask);  // the inverse, in PC_AOV_* order

// A technique's layers followed by the AOVs of `aov_mask`, in PC_AOV_* order.
FilmLayout make_film_layout(const std::vector<FilmLayer>& technique_layers, uint32_t aov_mask, uint32_t pixels);
// Where the AOV pass writes (offsets of the mask's AOVs in the film, PC_INVALID for the others).
AovHeader aov_header(const FilmLayout& layout, const double origin[3]);
