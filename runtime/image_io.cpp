#include "runtime/image_io.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <stdexcept>

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfInputFile.h>
#include <ImfIntAttribute.h>
#include <ImfOutputFile.h>
#include <ImfStringAttribute.h>
#include <png.h>

#include "runtime/atomic_file.h"
#include "runtime/errors.h"

namespace {

uint8_t to_srgb8(float linear) {
  float c = std::clamp(std::isfinite(linear) ? linear : 0.0f, 0.0f, 1.0f);
  float s = c <= 0.0031308f ? 12.92f * c : 1.055f * std::pow(c, 1.0f / 2.4f) - 0.055f;
  return uint8_t(std::lround(s * 255.0f));
}

// Adds R, G, B slices for an interleaved width * 3 float buffer to fb under names prefix + "R" etc.
// base is the address of pixel (0, 0) of the data window (it may lie outside the buffer).
void insert_rgb_slices(Imf::FrameBuffer& fb, const std::string& prefix, char* base, uint32_t width) {
  size_t xs = 3 * sizeof(float), ys = xs * width;
  fb.insert(prefix + "R", Imf::Slice(Imf::FLOAT, base, xs, ys));
  fb.insert(prefix + "G", Imf::Slice(Imf::FLOAT, base + sizeof(float), xs, ys));
  fb.insert(prefix + "B", Imf::Slice(Imf::FLOAT, base + 2 * sizeof(float), xs, ys));
}

bool has_rgb_channels(const Imf::ChannelList& channels, const std::string& prefix) {
  for (const char* c : {"R", "G", "B"})
    if (!channels.findChannel(prefix + c)) return false;
  return true;
}

}  // namespace

void write_exr(const std::string& path, const Image& image) {
  bool variance = !image.variance.empty();
  if (variance && image.variance.size() != image.rgb.size())
    throw RuntimeFailure(path + ": the variance buffer does not match the image size");
  write_file_atomically(path, "the EXR file", [&](const std::string& tmp) {
    Imf::Header header(int(image.width), int(image.height));
    for (const char* c : {"R", "G", "B"}) header.channels().insert(c, Imf::Channel(Imf::FLOAT));
    if (variance)
      for (const char* c : {"variance.R", "variance.G", "variance.B"}) header.channels().insert(c, Imf::Channel(Imf::FLOAT));
    header.insert("spp", Imf::IntAttribute(image.spp));
    for (const auto& [key, value] : image.attributes) header.insert(key, Imf::StringAttribute(value));
    Imf::FrameBuffer fb;
    insert_rgb_slices(fb, "", reinterpret_cast<char*>(const_cast<float*>(image.rgb.data())), image.width);
    if (variance)
      insert_rgb_slices(fb, "variance.", reinterpret_cast<char*>(const_cast<float*>(image.variance.data())), image.width);
    Imf::OutputFile file(tmp.c_str(), header);
    file.setFrameBuffer(fb);
    file.writePixels(int(image.height));
  });
}

void write_png(const std::string& path, const Image& image) {
  std::vector<uint8_t> pixels(image.rgb.size());
  std::transform(image.rgb.begin(), image.rgb.end(), pixels.begin(), to_srgb8);
  write_file_atomically(path, "the PNG file", [&](const std::string& tmp) {
    png_image png{};
    png.version = PNG_IMAGE_VERSION;
    png.width = image.width;
    png.height = image.height;
    png.format = PNG_FORMAT_RGB;
    if (!png_image_write_to_file(&png, tmp.c_str(), 0, pixels.data(), 0, nullptr)) throw std::runtime_error(png.message);
  });
}

Image read_exr(const std::string& path) {
  try {
    Imf::InputFile file(path.c_str());
    const Imf::ChannelList& channels = file.header().channels();
    // Without this check OpenEXR would silently fill missing channels with zeros.
    if (!has_rgb_channels(channels, "")) throw UsageError(path + ": not an RGB EXR file (no R, G and B channels)");
    Imath::Box2i dw = file.header().dataWindow();
    Image image;
    image.width = uint32_t(dw.max.x - dw.min.x + 1);
    image.height = uint32_t(dw.max.y - dw.min.y + 1);
    size_t floats = size_t(image.width) * image.height * 3;
    image.rgb.assign(floats, 0.0f);
    if (auto* spp = file.header().findTypedAttribute<Imf::IntAttribute>("spp")) image.spp = spp->value();
    for (auto it = file.header().begin(); it != file.header().end(); ++it)
      if (auto* s = dynamic_cast<const Imf::StringAttribute*>(&it.attribute())) image.attributes[it.name()] = s->value();
    // Slices are addressed from pixel (0, 0), so shift the base by the data window's origin.
    ptrdiff_t origin = (ptrdiff_t(dw.min.x) + ptrdiff_t(dw.min.y) * image.width) * 3 * ptrdiff_t(sizeof(float));
    Imf::FrameBuffer fb;
    insert_rgb_slices(fb, "", reinterpret_cast<char*>(image.rgb.data()) - origin, image.width);
    if (has_rgb_channels(channels, "variance.")) {
      image.variance.assign(floats, 0.0f);
      insert_rgb_slices(fb, "variance.", reinterpret_cast<char*>(image.variance.data()) - origin, image.width);
    }
    file.setFrameBuffer(fb);
    file.readPixels(dw.min.y, dw.max.y);
    return image;
  } catch (const UsageError&) {
    throw;
  } catch (const std::exception& e) {
    throw UsageError(path + ": cannot read the EXR file: " + e.what());
  }
}
