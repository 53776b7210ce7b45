// Writing the film: OpenEXR (32-bit float RGB, sample count in the header) and an sRGB PNG preview.
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
};

void write_exr(const std::string& path, const Image& image);  // RuntimeFailure on I/O errors
void write_png(const std::string& path, const Image& image);  // RuntimeFailure on I/O errors
Image read_exr(const std::string& path);                      // UsageError if unreadable
