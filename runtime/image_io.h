// Writing the film: OpenEXR (32-bit float RGB, sample count in the header, optionally a per-pixel
// variance layer) and an sRGB PNG preview.
// Both write to a temporary file beside the target and rename it, so no partial file is ever left.
#pragma once
#include <cstdint>
#include <map>
#include <string>
#include <vector>

struct Image {
  uint32_t width = 0, height = 0;
  std::vector<float> rgb;  // width * height * 3, row 0 at the top
  std::map<std::string, std::string> attributes;  // string attributes of the EXR header
  int spp = 0;                                    // written as the int attribute "spp"
  // Empty, or width * height * 3 like rgb: per pixel and channel, the variance of the pixel's mean
  // (not of single samples). Stored as the FLOAT channels variance.R, variance.G, variance.B.
  std::vector<float> variance;
};

void write_exr(const std::string& path, const Image& image);  // RuntimeFailure on I/O errors
void write_png(const std::string& path, const Image& image);  // RuntimeFailure on I/O errors
// UsageError if unreadable or without R, G, B channels. variance is read when all of variance.R,
// variance.G and variance.B are present, else left empty.
Image read_exr(const std::string& path);
