// SPDX-License-Identifier: MIT
#include "io/png_image.h"

#include <cmath>
#include <limits>
#include <stdexcept>

#include <gtest/gtest.h>

#include "tests/io/io_test_paths.h"

namespace nfield::io {
namespace {
using testing::data_path;
using testing::expect_error;
using testing::file_names;
using testing::scratch_dir;

// A 3×2 RGB PNG made by hand (Python's zlib), so the reader is checked against something
// VTK did not write. Top row: red, green, blue; bottom row: white, black, (128, 64, 32).
const unsigned char kHandMadePng[] = {
    0x89, 0x50, 0x4e, 0x47, 0x0d, 0x0a, 0x1a, 0x0a, 0x00, 0x00, 0x00, 0x0d, 0x49, 0x48, 0x44, 0x52,
    0x00, 0x00, 0x00, 0x03, 0x00, 0x00, 0x00, 0x02, 0x08, 0x02, 0x00, 0x00, 0x00, 0x12, 0x16, 0xf1,
    0x4d, 0x00, 0x00, 0x00, 0x15, 0x49, 0x44, 0x41, 0x54, 0x78, 0x9c, 0x63, 0xf8, 0xcf, 0xc0, 0xc0,
    0x00, 0xc1, 0xff, 0xff, 0x83, 0xe8, 0x06, 0x07, 0x05, 0x00, 0x46, 0xef, 0x06, 0xdb, 0x67, 0x08,
    0x17, 0x5c, 0x00, 0x00, 0x00, 0x00, 0x49, 0x45, 0x4e, 0x44, 0xae, 0x42, 0x60, 0x82};

// Random values on the 8-bit levels, so that they survive a round trip.
Image random_image(int width, int height, int channels) {
  Image im{width, height, channels, {}};
  im.pixels =
      ((Eigen::MatrixXf::Random(width * height, channels).array() + 1) * 127.5f).round().matrix() /
      255.f;
  return im;
}

TEST(PngImage, ReadsTopLeftPixelFirst) {
  const auto dir = scratch_dir();
  testing::write_text(dir / "hand.png", std::string(reinterpret_cast<const char*>(kHandMadePng),
                                                    sizeof kHandMadePng));
  const Image im = read_png(dir / "hand.png");
  EXPECT_EQ(im.width, 3);
  EXPECT_EQ(im.height, 2);
  EXPECT_EQ(im.channels, 3);
  Eigen::MatrixXf expected(6, 3);
  expected << 255, 0, 0, 0, 255, 0, 0, 0, 255, 255, 255, 255, 0, 0, 0, 128, 64, 32;
  EXPECT_TRUE(im.pixels.isApprox(expected / 255.f)) << im.pixels;
}

TEST(PngImage, RoundTripsGreyRgbAndRgba) {
  const auto dir = scratch_dir();
  for (int channels : {1, 2, 3, 4}) {
    const Image im = random_image(5, 3, channels);  // asymmetric: 5 wide, 3 high
    write_png(dir / "a.png", im);
    const Image back = read_png(dir / "a.png");
    EXPECT_EQ(back.width, 5);
    EXPECT_EQ(back.height, 3);
    EXPECT_EQ(back.channels, channels);
    EXPECT_LT((back.pixels - im.pixels).cwiseAbs().maxCoeff(), 1e-6) << channels;
  }
  EXPECT_EQ(file_names(dir), std::vector<std::string>{"a.png"});
}

TEST(PngImage, ClampsValuesWhenWriting) {
  const auto dir = scratch_dir();
  Image im{4, 1, 1, Eigen::MatrixXf(4, 1)};
  im.pixels << -1, 2, std::numeric_limits<float>::quiet_NaN(), 0.5;
  write_png(dir / "c.png", im);
  const Image back = read_png(dir / "c.png");
  EXPECT_EQ(back.pixels(0, 0), 0);
  EXPECT_EQ(back.pixels(1, 0), 1);
  EXPECT_EQ(back.pixels(2, 0), 0);
  EXPECT_NEAR(back.pixels(3, 0), 0.5, 0.51 / 255);
}

TEST(PngImage, ReadsCameraman) {
  const Image im = read_png(data_path("images/camera.png"));
  EXPECT_EQ(im.width, 512);
  EXPECT_EQ(im.height, 512);
  EXPECT_EQ(im.channels, 1);
  EXPECT_GE(im.pixels.minCoeff(), 0);
  EXPECT_LE(im.pixels.maxCoeff(), 1);
  EXPECT_GT(im.pixels.maxCoeff() - im.pixels.minCoeff(), 0.5);
}

TEST(PngImage, ScalarFieldRowZeroIsTheTopRow) {
  const auto dir = scratch_dir();
  Eigen::MatrixXd field(2, 3);
  field << -1, 0, 1, 2, 3, 4;
  write_scalar_png(dir / "f.png", field);
  const Image grey = read_png(dir / "f.png");
  EXPECT_EQ(grey.width, 3);
  EXPECT_EQ(grey.height, 2);
  EXPECT_EQ(grey.channels, 1);
  for (int p = 0; p < 6; ++p) EXPECT_NEAR(grey.pixels(p, 0), p / 5.0, 0.5 / 255) << p;

  // A fixed range clamps.
  const Image fixed = colorize(field, {std::pair(0.0, 2.0), Colormap::kGrey});
  EXPECT_EQ(fixed.pixels(0, 0), 0);
  EXPECT_EQ(fixed.pixels(1, 0), 0);
  EXPECT_EQ(fixed.pixels(2, 0), 0.5);
  EXPECT_EQ(fixed.pixels(5, 0), 1);
}

TEST(PngImage, Colormaps) {
  Eigen::MatrixXd field(1, 3);
  field << -2, 0, 1;
  const Image viridis = colorize(field, {std::nullopt, Colormap::kViridis});
  EXPECT_EQ(viridis.channels, 3);
  EXPECT_TRUE(viridis.pixels.row(0).isApprox(Eigen::RowVector3f(0.267f, 0.004f, 0.329f)));
  EXPECT_TRUE(viridis.pixels.row(2).isApprox(Eigen::RowVector3f(0.992f, 0.906f, 0.145f)));
  // Diverging: symmetric about 0 by default, so 0 is the middle colour and -2 the blue end.
  const Image diverging = colorize(field, {std::nullopt, Colormap::kDiverging});
  EXPECT_TRUE(diverging.pixels.row(1).isApprox(Eigen::RowVector3f(0.865f, 0.865f, 0.865f)));
  EXPECT_TRUE(diverging.pixels.row(0).isApprox(Eigen::RowVector3f(0.230f, 0.299f, 0.754f)));
  EXPECT_GT(diverging.pixels(2, 0), diverging.pixels(2, 2));  // reddish
}

// Each output pixel is its block's mean; the row and column past the last whole block go.
TEST(PngImage, BoxDownsample) {
  Image image{5, 4, 1, Eigen::MatrixXf(20, 1)};
  for (int i = 0; i < 20; ++i) image.pixels(i, 0) = static_cast<float>(i);
  const Image half = box_downsample(image, 2);
  ASSERT_EQ(half.width, 2);
  ASSERT_EQ(half.height, 2);
  EXPECT_FLOAT_EQ(half.pixels(0, 0), (0 + 1 + 5 + 6) / 4.f);
  EXPECT_FLOAT_EQ(half.pixels(1, 0), (2 + 3 + 7 + 8) / 4.f);
  EXPECT_FLOAT_EQ(half.pixels(3, 0), (12 + 13 + 17 + 18) / 4.f);
  EXPECT_EQ(box_downsample(image, 1).pixels, image.pixels);
  EXPECT_THROW(box_downsample(image, 0), std::invalid_argument);
  EXPECT_THROW(box_downsample(image, 5), std::invalid_argument);
}

// The central crop keeps rows and columns in place; the extra odd column goes at the right.
TEST(PngImage, CentralCropAndChannels) {
  Image image{5, 4, 4, Eigen::MatrixXf(20, 4)};
  for (int i = 0; i < 20; ++i) image.pixels.row(i) << 0.01f * i, 0.2f, 0.3f, 0.9f;
  const Image crop = central_crop(image, 2, 2);
  ASSERT_EQ(crop.width, 2);
  ASSERT_EQ(crop.height, 2);
  EXPECT_EQ(crop.pixels.row(0), image.pixels.row(1 * 5 + 1));
  EXPECT_EQ(crop.pixels.row(3), image.pixels.row(2 * 5 + 2));
  EXPECT_EQ(central_crop(image, 10, 3).width, 5);
  EXPECT_EQ(central_crop(image, 10, 3).height, 3);
  const Image grey = with_channels(crop, 1);
  ASSERT_EQ(grey.channels, 1);
  EXPECT_FLOAT_EQ(grey.pixels(0, 0), (0.06f + 0.2f + 0.3f) / 3);  // alpha dropped
  const Image rgb = with_channels(with_channels(image, 1), 3);
  ASSERT_EQ(rgb.channels, 3);
  EXPECT_EQ(rgb.pixels.col(0), rgb.pixels.col(2));
  Image grey_alpha{1, 1, 2, Eigen::MatrixXf(1, 2)};
  grey_alpha.pixels << 0.25f, 1.0f;
  EXPECT_EQ(with_channels(grey_alpha, 1).pixels(0, 0), 0.25f);
  EXPECT_EQ(with_channels(grey_alpha, 3).pixels(0, 1), 0.25f);
  EXPECT_THROW(central_crop(image, 0, 2), std::invalid_argument);
  EXPECT_THROW(with_channels(image, 2), std::invalid_argument);
}

TEST(PngImage, Errors) {
  const auto dir = scratch_dir();
  expect_error<std::runtime_error>([&] { read_png(dir / "none.png"); },
                                   {"none.png", "no such file"});
  testing::write_text(dir / "text.png", "not a png");
  expect_error<std::runtime_error>([&] { read_png(dir / "text.png"); }, {"text.png", "not a PNG"});
  expect_error<std::invalid_argument>(
      [&] {
        write_png(dir / "bad.png", Image{2, 2, 3, Eigen::MatrixXf::Zero(3, 3)});
      },
      {"bad.png"});
  expect_error<std::invalid_argument>(
      [&] {
        colorize(Eigen::MatrixXd::Zero(2, 2), {std::pair(1.0, 1.0), Colormap::kGrey});
      },
      {"range"});
  expect_error<std::runtime_error>(
      [&] {
        write_png(dir / "no" / "x.png", Image{1, 1, 1, Eigen::MatrixXf::Zero(1, 1)});
      },
      {"x.png"});
}

}  // namespace
}  // namespace nfield::io
