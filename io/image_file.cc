// SPDX-License-Identifier: MIT
#include "io/image_file.h"

#include <array>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include <webp/decode.h>

#include "io/text.h"

namespace nfield::io {
namespace fs = std::filesystem;
namespace {

std::runtime_error failure(const fs::path& path, const std::string& why) {
  return std::runtime_error("read_image: '" + path.string() + "': " + why);
}

Image read_webp(const fs::path& path, const std::vector<uint8_t>& bytes) {
  WebPBitstreamFeatures features;
  if (WebPGetFeatures(bytes.data(), bytes.size(), &features) != VP8_STATUS_OK)
    throw failure(path, "a WebP header that does not decode");
  const int channels = features.has_alpha ? 4 : 3;
  int width = 0, height = 0;
  const std::unique_ptr<uint8_t, void (*)(void*)> rgb(
      channels == 4 ? WebPDecodeRGBA(bytes.data(), bytes.size(), &width, &height)
                    : WebPDecodeRGB(bytes.data(), bytes.size(), &width, &height),
      WebPFree);
  if (!rgb || width < 1 || height < 1) throw failure(path, "the WebP data do not decode");
  Image image{width, height, channels, {}};
  // libwebp writes rows top first, channels interleaved: the transpose of our layout.
  const Eigen::Index pixels = Eigen::Index{width} * height;
  const Eigen::Map<const Eigen::Matrix<uint8_t, Eigen::Dynamic, Eigen::Dynamic>> interleaved(rgb.get(), channels,
                                                                                          pixels);
  image.pixels = interleaved.transpose().cast<float>() / 255.0f;
  return image;
}

}  // namespace

bool is_image_file_name(const fs::path& path) {
  const std::string extension = to_lower(path.extension().string());
  return extension == ".png" || extension == ".webp";
}

Image read_image(const fs::path& path) {
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) throw failure(path, "no such file");
  std::ifstream in(path, std::ios::binary);
  std::array<char, 12> head{};
  in.read(head.data(), head.size());
  if (in.gcount() >= 8 && std::memcmp(head.data(), "\x89PNG\r\n\x1a\n", 8) == 0) return read_png(path);
  if (in.gcount() == 12 && std::memcmp(head.data(), "RIFF", 4) == 0 && std::memcmp(head.data() + 8, "WEBP", 4) == 0) {
    const std::uintmax_t size = fs::file_size(path, ec);
    if (ec) throw failure(path, "cannot read the file: " + ec.message());
    std::vector<uint8_t> bytes(size);
    in.seekg(0);
    in.read(reinterpret_cast<char*>(bytes.data()), static_cast<std::streamsize>(size));
    if (in.gcount() != static_cast<std::streamsize>(size)) throw failure(path, "cannot read the file");
    return read_webp(path, bytes);
  }
  throw failure(path, "not a PNG or WebP file");
}

}  // namespace nfield::io
