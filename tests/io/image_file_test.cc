// SPDX-License-Identifier: MIT
#include "io/image_file.h"

#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <webp/encode.h>

#include "tests/io/io_test_paths.h"

namespace nfield::io {
namespace {
using testing::expect_error;
using testing::scratch_dir;

// A 3×2 lossless WebP written by another program (Pillow), so that the reader is checked
// against a file libwebp's decoder did not help make. Top row: red, green, blue; bottom row:
// white, black, (128, 64, 32).
const unsigned char kHandMadeWebp[] = {
    0x52, 0x49, 0x46, 0x46, 0x3a, 0x00, 0x00, 0x00, 0x57, 0x45, 0x42, 0x50, 0x56, 0x50, 0x38, 0x4c,
    0x2d, 0x00, 0x00, 0x00, 0x2f, 0x02, 0x40, 0x00, 0x00, 0x2f, 0x20, 0x10, 0x20, 0x48, 0xf3, 0x1f,
    0x65, 0x43, 0x40, 0x50, 0x74, 0xdd, 0x72, 0x02, 0x01, 0x82, 0x14, 0xff, 0x91, 0xe6, 0x3f, 0x40,
    0x6c, 0x72, 0x6c, 0x15, 0x28, 0x48, 0xdb, 0x80, 0xc5, 0xdd, 0x53, 0xb2, 0x88, 0xfe, 0xc7, 0xd5,
    0x01, 0x00};

std::string bytes_of(const unsigned char* data, std::size_t size) {
  return std::string(reinterpret_cast<const char*>(data), size);
}

// Random 8-bit pixels, rows top first, channels interleaved (libwebp's layout), written as a
// lossless WebP of 3 or 4 channels.
std::vector<uint8_t> random_pixels(int width, int height, int channels, unsigned seed) {
  std::vector<uint8_t> pixels(static_cast<std::size_t>(width * height * channels));
  for (auto& p : pixels) p = static_cast<uint8_t>((seed = seed * 1103515245u + 12345u) >> 16);
  return pixels;
}
std::string lossless_webp(const std::vector<uint8_t>& pixels, int width, int height, int channels) {
  uint8_t* out = nullptr;
  const std::size_t size = channels == 4 ? WebPEncodeLosslessRGBA(pixels.data(), width, height, width * 4, &out)
                                         : WebPEncodeLosslessRGB(pixels.data(), width, height, width * 3, &out);
  std::string file(reinterpret_cast<const char*>(out), size);
  WebPFree(out);
  return file;
}

TEST(ImageFile, ReadsAWebpTopLeftPixelFirst) {
  const auto dir = scratch_dir();
  testing::write_text(dir / "hand.webp", bytes_of(kHandMadeWebp, sizeof kHandMadeWebp));
  const Image im = read_image(dir / "hand.webp");
  EXPECT_EQ(im.width, 3);
  EXPECT_EQ(im.height, 2);
  EXPECT_EQ(im.channels, 3);
  Eigen::MatrixXf expected(6, 3);
  expected << 255, 0, 0, 0, 255, 0, 0, 0, 255, 255, 255, 255, 0, 0, 0, 128, 64, 32;
  EXPECT_TRUE(im.pixels.isApprox(expected / 255.f)) << im.pixels;
}

TEST(ImageFile, LosslessWebpRoundTripsRgbAndRgba) {
  const auto dir = scratch_dir();
  for (int channels : {3, 4}) {
    const int width = 7, height = 5;  // asymmetric, odd
    const std::vector<uint8_t> pixels = random_pixels(width, height, channels, 17u + channels);
    testing::write_text(dir / "a.webp", lossless_webp(pixels, width, height, channels));
    const Image im = read_image(dir / "a.webp");
    ASSERT_EQ(im.width, width);
    ASSERT_EQ(im.height, height);
    ASSERT_EQ(im.channels, channels);
    for (int r = 0; r < height; ++r)
      for (int c = 0; c < width; ++c)
        for (int k = 0; k < channels; ++k)
          ASSERT_EQ(im.pixels(r * width + c, k) * 255.f,
                    static_cast<float>(pixels[static_cast<std::size_t>((r * width + c) * channels + k)]))
              << "row " << r << " column " << c << " channel " << k;
  }
}

TEST(ImageFile, ReadsPngByItsBytesNotItsName) {
  const auto dir = scratch_dir();
  Image im{4, 3, 3, Eigen::MatrixXf::Zero(12, 3)};
  im.pixels(5, 1) = 1.0f;
  write_png(dir / "picture.webp", im);  // a PNG under another name
  const Image back = read_image(dir / "picture.webp");
  EXPECT_EQ(back.width, 4);
  EXPECT_EQ(back.height, 3);
  EXPECT_EQ(back.pixels, im.pixels);
}

TEST(ImageFile, Errors) {
  const auto dir = scratch_dir();
  expect_error<std::runtime_error>([&] { read_image(dir / "none.webp"); }, {"none.webp", "no such file"});
  testing::write_text(dir / "text.png", "not a picture at all");
  expect_error<std::runtime_error>([&] { read_image(dir / "text.png"); }, {"text.png", "not a PNG or WebP file"});
  // A WebP header followed by garbage, and one cut short.
  std::string broken = bytes_of(kHandMadeWebp, 20) + std::string(46, '\x55');
  testing::write_text(dir / "broken.webp", broken);
  expect_error<std::runtime_error>([&] { read_image(dir / "broken.webp"); }, {"broken.webp", "WebP"});
  testing::write_text(dir / "short.webp", bytes_of(kHandMadeWebp, 30));
  expect_error<std::runtime_error>([&] { read_image(dir / "short.webp"); }, {"short.webp", "WebP"});
}

TEST(ImageFile, PictureFileNames) {
  EXPECT_TRUE(is_image_file_name("a/b.png"));
  EXPECT_TRUE(is_image_file_name("B.WebP"));
  EXPECT_FALSE(is_image_file_name("c.jpg"));
  EXPECT_FALSE(is_image_file_name("png"));
}

}  // namespace
}  // namespace nfield::io
