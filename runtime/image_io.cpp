#include "runtime/image_io.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <set>
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

std::string exr_channel_name(const std::string& layer, const std::string& channel) {
  return layer.empty() ? channel : layer + "." + channel;
}

std::string layer_label(const ImageLayer& layer) {
  return layer.name.empty() ? "the layer of unprefixed channels" : "layer \"" + layer.name + "\"";
}

// Adds one slice per channel of an interleaved buffer of channels.size() values of `type` (4-byte FLOAT or
// UINT) per pixel; base is the address of pixel (0, 0) of the data window.
void insert_layer_slices(Imf::FrameBuffer& fb, const std::string& layer, const std::vector<std::string>& channels,
                         Imf::PixelType type, char* base, uint32_t width) {
  size_t xs = channels.size() * 4, ys = xs * width;
  for (size_t c = 0; c < channels.size(); ++c)
    fb.insert(exr_channel_name(layer, channels[c]), Imf::Slice(type, base + 4 * c, xs, ys));
}

// The layers must fit the image before anything is written: a wrong size would make OpenEXR read past
// a buffer, and two layers writing one channel name would make a file that reads back differently.
void check_layers(const std::string& path, const Image& image) {
  size_t pixels = size_t(image.width) * image.height;
  std::set<std::string> names = {"R", "G", "B"};
  if (!image.variance.empty()) names.insert({"variance.R", "variance.G", "variance.B"});
  for (const ImageLayer& layer : image.layers) {
    std::string what = path + ": " + layer_label(layer);
    if (layer.channels.empty()) throw RuntimeFailure(what + " has no channels");
    if (layer.values.size() != pixels * layer.channels.size())
      throw RuntimeFailure(what + " holds " + std::to_string(layer.values.size()) + " values where " +
                           std::to_string(image.width) + " x " + std::to_string(image.height) + " pixels of " +
                           std::to_string(layer.channels.size()) + " channels need " +
                           std::to_string(pixels * layer.channels.size()));
    for (const std::string& c : layer.channels) {
      std::string name = exr_channel_name(layer.name, c);
      // A '.' in the channel would move it into another layer when the file is read back.
      if (c.find('.') != std::string::npos || name.empty())
        throw RuntimeFailure(what + ": bad channel name \"" + c + "\"");
      if (!names.insert(name).second) throw RuntimeFailure(what + ": channel " + name + " is written twice");
    }
    if (layer.integer)
      for (size_t i = 0; i < layer.values.size(); ++i) {
        float v = layer.values[i];
        if (!(v >= 0.0f && v < 4294967296.0f && v == std::floor(v))) {
          size_t p = i / layer.channels.size();
          throw RuntimeFailure(what + ": value " + std::to_string(v) + " of pixel (" + std::to_string(p % image.width) +
                               ", " + std::to_string(p / image.width) + ") is not an integer in [0, 2^32)");
        }
      }
  }
}

// Channel order within a layer: the usual ones in their usual order, then the others alphabetically.
int channel_rank(const std::string& c) {
  static const char* known[] = {"R", "G", "B", "A", "X", "Y", "Z", "U", "V", "id"};
  for (int i = 0; i < int(std::size(known)); ++i)
    if (c == known[i]) return i;
  return int(std::size(known));
}

}  // namespace

const ImageLayer* find_layer(const Image& image, const std::string& name) {
  for (const ImageLayer& layer : image.layers)
    if (layer.name == name) return &layer;
  return nullptr;
}

void write_exr(const std::string& path, const Image& image) {
  if (image.rgb.size() != size_t(image.width) * image.height * 3)
    throw RuntimeFailure(path + ": the RGB buffer does not match the image size");
  bool variance = !image.variance.empty();
  if (variance && image.variance.size() != image.rgb.size())
    throw RuntimeFailure(path + ": the variance buffer does not match the image size");
  check_layers(path, image);
  // OpenEXR writes UINT channels from 32-bit unsigned integers: the integer layers' values converted.
  std::vector<std::vector<uint32_t>> ints(image.layers.size());
  for (size_t l = 0; l < image.layers.size(); ++l)
    if (image.layers[l].integer)
      for (float v : image.layers[l].values) ints[l].push_back(uint32_t(v));
  write_file_atomically(path, "the EXR file", [&](const std::string& tmp) {
    Imf::Header header(int(image.width), int(image.height));
    for (const char* c : {"R", "G", "B"}) header.channels().insert(c, Imf::Channel(Imf::FLOAT));
    if (variance)
      for (const char* c : {"variance.R", "variance.G", "variance.B"}) header.channels().insert(c, Imf::Channel(Imf::FLOAT));
    for (const ImageLayer& layer : image.layers)
      for (const std::string& c : layer.channels)
        header.channels().insert(exr_channel_name(layer.name, c), Imf::Channel(layer.integer ? Imf::UINT : Imf::FLOAT));
    header.insert("spp", Imf::IntAttribute(image.spp));
    for (const auto& [key, value] : image.attributes) header.insert(key, Imf::StringAttribute(value));
    Imf::FrameBuffer fb;
    insert_rgb_slices(fb, "", reinterpret_cast<char*>(const_cast<float*>(image.rgb.data())), image.width);
    if (variance)
      insert_rgb_slices(fb, "variance.", reinterpret_cast<char*>(const_cast<float*>(image.variance.data())), image.width);
    for (size_t l = 0; l < image.layers.size(); ++l) {
      const ImageLayer& layer = image.layers[l];
      char* base = layer.integer ? reinterpret_cast<char*>(ints[l].data())
                                 : reinterpret_cast<char*>(const_cast<float*>(layer.values.data()));
      insert_layer_slices(fb, layer.name, layer.channels, layer.integer ? Imf::UINT : Imf::FLOAT, base, image.width);
    }
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
    bool variance = has_rgb_channels(channels, "variance.");
    if (variance) {
      image.variance.assign(floats, 0.0f);
      insert_rgb_slices(fb, "variance.", reinterpret_cast<char*>(image.variance.data()) - origin, image.width);
    }
    // Every other channel, grouped into layers by the name before its last '.'.
    std::map<std::string, std::vector<std::pair<std::string, Imf::PixelType>>> groups;
    for (auto it = channels.begin(); it != channels.end(); ++it) {
      std::string name = it.name();
      if (name == "R" || name == "G" || name == "B") continue;
      if (variance && (name == "variance.R" || name == "variance.G" || name == "variance.B")) continue;
      if (it.channel().xSampling != 1 || it.channel().ySampling != 1) continue;
      size_t dot = name.rfind('.');
      std::string layer = dot == std::string::npos ? "" : name.substr(0, dot);
      groups[layer].emplace_back(dot == std::string::npos ? name : name.substr(dot + 1), it.channel().type);
    }
    size_t pixels = size_t(image.width) * image.height;
    std::vector<std::vector<uint32_t>> ints;  // the integer layers' pixels as OpenEXR reads them
    for (auto& [name, group] : groups) {
      std::sort(group.begin(), group.end(), [](const auto& a, const auto& b) {
        int ra = channel_rank(a.first), rb = channel_rank(b.first);
        return ra != rb ? ra < rb : a.first < b.first;
      });
      ImageLayer layer;
      layer.name = name;
      layer.integer = std::all_of(group.begin(), group.end(), [](const auto& c) { return c.second == Imf::UINT; });
      for (const auto& c : group) layer.channels.push_back(c.first);
      size_t n = layer.channels.size();
      layer.values.assign(pixels * n, 0.0f);
      ints.emplace_back(layer.integer ? pixels * n : 0);
      char* data = layer.integer ? reinterpret_cast<char*>(ints.back().data()) : reinterpret_cast<char*>(layer.values.data());
      ptrdiff_t layer_origin = (ptrdiff_t(dw.min.x) + ptrdiff_t(dw.min.y) * image.width) * ptrdiff_t(n * 4);
      insert_layer_slices(fb, name, layer.channels, layer.integer ? Imf::UINT : Imf::FLOAT, data - layer_origin, image.width);
      image.layers.push_back(std::move(layer));
    }
    file.setFrameBuffer(fb);
    file.readPixels(dw.min.y, dw.max.y);
    for (size_t l = 0; l < image.layers.size(); ++l)
      if (image.layers[l].integer) std::copy(ints[l].begin(), ints[l].end(), image.layers[l].values.begin());
    return image;
  } catch (const UsageError&) {
    throw;
  } catch (const std::exception& e) {
    throw UsageError(path + ": cannot read the EXR file: " + e.what());
  }
}
