// Writing the film: OpenEXR (32-bit float RGB, sample count in the header, optionally a per-pixel
// variance layer and further named layers such as albedo, normal or ids) and an sRGB PNG preview.
// Both write to a temporary file beside the target and rename it, so no partial file is ever left.
#pragma once
#include <cstdint>
#include <map>
#include <string>
#include <vector>

// A named group of EXR channels beside the beauty: channel c of layer "albedo" is the EXR channel
// "albedo.c". A layer with an empty name holds unprefixed channels other than R, G, B (e.g. "A").
struct ImageLayer {
  std::string name;                   // "albedo", "normal", "depth", "object_id"
  std::vector<std::string> channels;  // {"R","G","B"}, {"X","Y","Z"}, {"Z"}, {"U","V"}, {"id"}
  std::vector<float> values;          // width * height * channels.size(), interleaved per pixel, row 0 at top
  // Stored as EXR UINT channels (ids): values must be integers in [0, 2^32), and read back exactly when
  // below 2^24 (the integers a float holds exactly).
  bool integer = false;
};

struct Image {
  uint32_t width = 0, height = 0;
  std::vector<float> rgb;  // width * height * 3, row 0 at the top
  std::map<std::string, std::string> attributes;  // string attributes of the EXR header
  int spp = 0;                                    // written as the int attribute "spp"
  // Empty, or width * height * 3 like rgb: per pixel and channel, the variance of the pixel's mean
  // (not of single samples). Stored as the FLOAT channels variance.R, variance.G, variance.B.
  std::vector<float> variance;
  std::vector<ImageLayer> layers;  // written after R, G, B (and variance); PNG ignores them
};

// The layer called name, or nullptr.
const ImageLayer* find_layer(const Image& image, const std::string& name);

// RuntimeFailure on I/O errors and on buffers whose sizes do not match the image (naming the path and
// the layer), layer channels that clash with each other or with R, G, B and variance, and integer
// layers holding other values than integers in [0, 2^32).
void write_exr(const std::string& path, const Image& image);
void write_png(const std::string& path, const Image& image);  // RuntimeFailure on I/O errors
// UsageError if unreadable or without R, G, B channels. variance is read when all of variance.R,
// variance.G and variance.B are present, else left empty (and any of them in a layer "variance"). Every
// other channel goes into layers, grouped
// by the name before its last '.' (in the file's order of names, i.e. alphabetical), channels in the
// order R, G, B, A, X, Y, Z, U, V, id where present and alphabetical after those; a layer whose
// channels are all UINT is an integer layer, others are read as float. Channels stored at a reduced
// resolution (x or y sampling other than 1) are skipped. attributes gets the header's string
// attributes and spp its int attribute "spp" (0 without one).
Image read_exr(const std::string& path);
