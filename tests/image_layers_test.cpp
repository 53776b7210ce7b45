// EXR layers (runtime/image_io.h): float and integer layers written and read back, channel order and
// grouping, unprefixed channels, partial variance, data windows off the origin, half channels, header
// attributes; layers that do not fit the image are refused before any file is written.
#include <filesystem>
#include <string>

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfInputFile.h>
#include <ImfOutputFile.h>
#include <gtest/gtest.h>

#include "runtime/errors.h"
#include "runtime/image_io.h"
#include "test_support.h"

namespace fs = std::filesystem;

namespace {

std::vector<float> ramp(size_t n, float scale, float offset = 0) {
  std::vector<float> v(n);
  for (size_t i = 0; i < n; ++i) v[i] = offset + scale * float(i);
  return v;
}

Image small_image(uint32_t w = 5, uint32_t h = 3) {
  Image image;
  image.width = w;
  image.height = h;
  image.rgb = ramp(size_t(w) * h * 3, 0.25f);
  return image;
}

// The message of the RuntimeFailure that write_exr throws, or "".
std::string write_error(const std::string& path, const Image& image) {
  try {
    write_exr(path, image);
  } catch (const RuntimeFailure& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST(ImageLayers, FloatAndIntegerLayersRoundTrip) {
  Image image = small_image();
  size_t pixels = size_t(image.width) * image.height;
  image.spp = 17;
  image.attributes = {{"renderer", "pathcl test"}, {"integrator", "path"}};
  image.variance = ramp(pixels * 3, 1e-3f);
  image.layers.push_back({"albedo", {"R", "G", "B"}, ramp(pixels * 3, 0.01f), false});
  image.layers.push_back({"normal", {"X", "Y", "Z"}, ramp(pixels * 3, -0.02f, 0.5f), false});
  image.layers.push_back({"depth", {"Z"}, ramp(pixels, 1.5f), false});
  image.layers.push_back({"uv", {"U", "V"}, ramp(pixels * 2, 0.03f), false});
  std::vector<float> ids = ramp(pixels, 1000.0f);
  ids.back() = 16777215.0f;  // 2^24 - 1: still exact in a float
  image.layers.push_back({"object_id", {"id"}, ids, true});
  std::string path = temp_dir() + "/layers.exr";
  write_exr(path, image);

  Image back = read_exr(path);
  EXPECT_EQ(back.width, image.width);
  EXPECT_EQ(back.height, image.height);
  EXPECT_EQ(back.rgb, image.rgb);
  EXPECT_EQ(back.variance, image.variance);
  EXPECT_EQ(back.spp, 17);
  EXPECT_EQ(back.attributes.at("renderer"), "pathcl test");
  EXPECT_EQ(back.attributes.at("integrator"), "path");
  EXPECT_EQ(back.attributes.count("spp"), 0u);  // an int attribute: in spp, not among the strings
  ASSERT_EQ(back.layers.size(), image.layers.size());
  // In the file's order of channel names, i.e. alphabetical.
  std::vector<std::string> names;
  for (const ImageLayer& l : back.layers) names.push_back(l.name);
  EXPECT_EQ(names, (std::vector<std::string>{"albedo", "depth", "normal", "object_id", "uv"}));
  for (const ImageLayer& want : image.layers) {
    const ImageLayer* got = find_layer(back, want.name);
    ASSERT_NE(got, nullptr) << want.name;
    EXPECT_EQ(got->channels, want.channels) << want.name;
    EXPECT_EQ(got->values, want.values) << want.name;
    EXPECT_EQ(got->integer, want.integer) << want.name;
  }
  EXPECT_EQ(find_layer(back, "missing"), nullptr);

  // The integer layer is a UINT channel in the file, the others FLOAT.
  Imf::InputFile file(path.c_str());
  const Imf::ChannelList& channels = file.header().channels();
  ASSERT_NE(channels.findChannel("object_id.id"), nullptr);
  EXPECT_EQ(channels.findChannel("object_id.id")->type, Imf::UINT);
  EXPECT_EQ(channels.findChannel("albedo.R")->type, Imf::FLOAT);
  EXPECT_EQ(channels.findChannel("uv.V")->type, Imf::FLOAT);

  // PNG ignores the layers.
  write_png(temp_dir() + "/layers.png", image);
  EXPECT_TRUE(fs::exists(temp_dir() + "/layers.png"));
}

TEST(ImageLayers, ChannelOrderAndUnprefixedChannels) {
  Image image = small_image(2, 2);
  // Written in an odd order: read back as X, Y, Z and R, G, B, A, then other names alphabetically.
  image.layers.push_back({"n", {"Z", "X", "Y"}, ramp(12, 1.0f), false});
  image.layers.push_back({"c", {"A", "B", "zeta", "G", "R", "alpha"}, ramp(24, 1.0f), false});
  image.layers.push_back({"", {"A"}, ramp(4, 0.5f), false});         // an unprefixed alpha channel
  image.layers.push_back({"a.b", {"V", "U"}, ramp(8, 2.0f), false});  // nested name: the prefix is "a.b"
  std::string path = temp_dir() + "/order.exr";
  write_exr(path, image);
  Image back = read_exr(path);

  const ImageLayer* n = find_layer(back, "n");
  ASSERT_NE(n, nullptr);
  EXPECT_EQ(n->channels, (std::vector<std::string>{"X", "Y", "Z"}));
  for (size_t p = 0; p < 4; ++p) {  // written Z, X, Y = 3p, 3p + 1, 3p + 2
    EXPECT_EQ(n->values[3 * p + 0], float(3 * p + 1));
    EXPECT_EQ(n->values[3 * p + 1], float(3 * p + 2));
    EXPECT_EQ(n->values[3 * p + 2], float(3 * p + 0));
  }
  const ImageLayer* c = find_layer(back, "c");
  ASSERT_NE(c, nullptr);
  EXPECT_EQ(c->channels, (std::vector<std::string>{"R", "G", "B", "A", "alpha", "zeta"}));
  EXPECT_EQ(c->values[0], 4.0f);  // R of pixel 0 was written as the fifth channel
  EXPECT_EQ(c->values[5], 2.0f);  // zeta of pixel 0 was the third
  const ImageLayer* unprefixed = find_layer(back, "");
  ASSERT_NE(unprefixed, nullptr);
  EXPECT_EQ(unprefixed->channels, (std::vector<std::string>{"A"}));
  EXPECT_EQ(unprefixed->values, ramp(4, 0.5f));
  const ImageLayer* ab = find_layer(back, "a.b");
  ASSERT_NE(ab, nullptr);
  EXPECT_EQ(ab->channels, (std::vector<std::string>{"U", "V"}));
  EXPECT_EQ(ab->values[0], 2.0f);
  EXPECT_EQ(ab->values[1], 0.0f);
  EXPECT_EQ(back.rgb, image.rgb);

  // A second round trip changes nothing.
  write_exr(path, back);
  Image again = read_exr(path);
  ASSERT_EQ(again.layers.size(), back.layers.size());
  for (size_t i = 0; i < back.layers.size(); ++i) {
    EXPECT_EQ(again.layers[i].name, back.layers[i].name);
    EXPECT_EQ(again.layers[i].channels, back.layers[i].channels);
    EXPECT_EQ(again.layers[i].values, back.layers[i].values);
  }
}

// A file of another program: data window off the origin, a half and a UINT channel, a partial variance.
TEST(ImageLayers, ForeignFileWithDataWindowHalfAndPartialVariance) {
  const int w = 4, h = 3, x0 = 2, y0 = 5;
  std::string path = temp_dir() + "/foreign.exr";
  {
    Imf::Header header(Imath::Box2i({0, 0}, {9, 9}), Imath::Box2i({x0, y0}, {x0 + w - 1, y0 + h - 1}));
    for (const char* c : {"R", "G", "B", "variance.R", "depth.Z"}) header.channels().insert(c, Imf::Channel(Imf::FLOAT));
    header.channels().insert("mask.Y", Imf::Channel(Imf::HALF));
    header.channels().insert("id.id", Imf::Channel(Imf::UINT));
    std::vector<float> rgb(w * h * 3, 1.0f), var(w * h, 0.5f), depth(w * h);
    std::vector<Imath::half> mask(w * h);
    std::vector<uint32_t> id(w * h);
    for (int i = 0; i < w * h; ++i) {
      depth[i] = float(i) + 0.25f;
      mask[i] = Imath::half(float(i) * 0.5f);
      id[i] = uint32_t(i * 7 + 3);
    }
    // Slices are addressed from pixel (0, 0): shift each base by the data window's origin.
    auto base = [&](auto* data, size_t elem, size_t per_pixel) {
      return reinterpret_cast<char*>(data) - (ptrdiff_t(x0) + ptrdiff_t(y0) * w) * ptrdiff_t(elem * per_pixel);
    };
    Imf::FrameBuffer fb;
    for (int c = 0; c < 3; ++c)
      fb.insert(std::string(1, "RGB"[c]), Imf::Slice(Imf::FLOAT, base(rgb.data(), 4, 3) + 4 * c, 12, 12 * w));
    fb.insert("variance.R", Imf::Slice(Imf::FLOAT, base(var.data(), 4, 1), 4, 4 * w));
    fb.insert("depth.Z", Imf::Slice(Imf::FLOAT, base(depth.data(), 4, 1), 4, 4 * w));
    fb.insert("mask.Y", Imf::Slice(Imf::HALF, base(mask.data(), 2, 1), 2, 2 * w));
    fb.insert("id.id", Imf::Slice(Imf::UINT, base(id.data(), 4, 1), 4, 4 * w));
    Imf::OutputFile file(path.c_str(), header);
    file.setFrameBuffer(fb);
    file.writePixels(h);
  }
  Image image = read_exr(path);
  ASSERT_EQ(image.width, uint32_t(w));
  ASSERT_EQ(image.height, uint32_t(h));
  EXPECT_TRUE(image.variance.empty());  // only variance.R: not a variance, but a layer
  const ImageLayer* var = find_layer(image, "variance");
  ASSERT_NE(var, nullptr);
  EXPECT_EQ(var->channels, std::vector<std::string>{"R"});
  EXPECT_EQ(var->values, std::vector<float>(w * h, 0.5f));
  const ImageLayer* depth = find_layer(image, "depth");
  const ImageLayer* mask = find_layer(image, "mask");
  const ImageLayer* id = find_layer(image, "id");
  ASSERT_TRUE(depth && mask && id);
  EXPECT_FALSE(mask->integer);
  EXPECT_TRUE(id->integer);
  for (int i = 0; i < w * h; ++i) {
    EXPECT_EQ(depth->values[i], float(i) + 0.25f);
    EXPECT_EQ(mask->values[i], float(i) * 0.5f);  // exact in a half
    EXPECT_EQ(id->values[i], float(i * 7 + 3));
  }
}

TEST(ImageLayers, LayersThatDoNotFitAreRefused) {
  std::string dir = temp_dir() + "/bad";
  fs::create_directories(dir);
  std::string path = dir + "/bad.exr";
  Image image = small_image();
  size_t pixels = size_t(image.width) * image.height;

  image.layers = {{"albedo", {"R", "G", "B"}, std::vector<float>(pixels * 3 - 1), false}};
  std::string e = write_error(path, image);
  EXPECT_NE(e.find(path), std::string::npos) << e;
  EXPECT_NE(e.find("layer \"albedo\""), std::string::npos) << e;
  EXPECT_NE(e.find("44 values"), std::string::npos) << e;
  EXPECT_NE(e.find("need 45"), std::string::npos) << e;

  image.layers = {{"object_id", {"id"}, std::vector<float>(pixels, 1.5f), true}};
  e = write_error(path, image);
  EXPECT_NE(e.find("layer \"object_id\""), std::string::npos) << e;
  EXPECT_NE(e.find("not an integer"), std::string::npos) << e;
  image.layers[0].values.assign(pixels, -1.0f);
  EXPECT_NE(write_error(path, image).find("not an integer"), std::string::npos);

  image.layers = {{"empty", {}, {}, false}};
  EXPECT_NE(write_error(path, image).find("no channels"), std::string::npos);

  image.layers = {{"x", {"a.b"}, std::vector<float>(pixels), false}};
  EXPECT_NE(write_error(path, image).find("bad channel name"), std::string::npos);

  // Channels that clash with the beauty, the variance or each other.
  image.layers = {{"", {"G"}, std::vector<float>(pixels), false}};
  EXPECT_NE(write_error(path, image).find("channel G is written twice"), std::string::npos);
  image.variance.assign(pixels * 3, 0.0f);
  image.layers = {{"variance", {"B"}, std::vector<float>(pixels), false}};
  EXPECT_NE(write_error(path, image).find("channel variance.B is written twice"), std::string::npos);
  image.variance.clear();
  image.layers = {{"a", {"Z"}, std::vector<float>(pixels), false}, {"a", {"Z"}, std::vector<float>(pixels), false}};
  EXPECT_NE(write_error(path, image).find("channel a.Z is written twice"), std::string::npos);

  image.layers.clear();
  image.rgb.pop_back();
  EXPECT_NE(write_error(path, image).find("RGB buffer"), std::string::npos);

  EXPECT_TRUE(fs::is_empty(dir));  // nothing written, not even a temporary file
}
