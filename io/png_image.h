// SPDX-License-Identifier: MIT
#pragma once
#include <filesystem>
#include <optional>
#include <utility>

#include <Eigen/Core>

namespace nfield::io {

// A picture as a person reads it: pixel (row r, column c), r = 0 the top row, is row
// r * width + c of `pixels`; each column one channel (1 grey, 2 grey+alpha, 3 RGB, 4 RGBA),
// values in [0, 1].
struct Image {
  int width = 0;
  int height = 0;
  int channels = 0;
  Eigen::MatrixXf pixels;  // (height * width) × channels
};

// Reads an 8- or 16-bit PNG of 1 to 4 channels (vtkPNGReader). Throws std::runtime_error
// naming `path` when it is missing or not a PNG.
Image read_png(const std::filesystem::path& path);

// Writes an 8-bit PNG of 1 to 4 channels (vtkPNGWriter) atomically (see io/atomic_write.h);
// values are clamped to [0, 1] and NaN written as 0. Throws std::invalid_argument for a
// malformed image and std::runtime_error naming `path` when writing fails.
void write_png(const std::filesystem::path& path, const Image& image);

// The central crop of min(width, image.width) × min(height, image.height) pixels (when the
// picture is larger by an odd count, the extra column or row is left at the right or bottom).
// Throws std::invalid_argument when width or height is below 1.
Image central_crop(const Image& image, int width, int height);

// The picture shrunk by an integer factor: each pixel the mean of a factor × factor block
// (area averaging, as a camera with larger pixels would see it). Rows and columns past the
// last whole block are dropped. Throws std::invalid_argument for a factor below 1 or above
// either side.
Image box_downsample(const Image& image, int factor);

// The picture with 1 channel (grey: the mean of R, G and B, or the grey channel) or 3 (RGB: a
// grey channel repeated); alpha is dropped. Throws std::invalid_argument for other counts.
Image with_channels(const Image& image, int channels);

// How write_scalar_png maps values to colours.
enum class Colormap {
  kGrey,       // black to white
  kViridis,    // dark blue, green, yellow (perceptually uniform)
  kDiverging,  // blue, white at the middle of the range, red
};
struct ScalarImageOptions {
  // Values mapped to the two ends of the colormap; outside values are clamped. Unset: the
  // field's finite minimum and maximum, or ±max|value| for kDiverging so that 0 is white.
  std::optional<std::pair<double, double>> range;
  Colormap colormap = Colormap::kGrey;
};

// A scalar field as a picture: field(r, c) is the pixel at row r (r = 0 the top row), column
// c. Grey (1 channel) for kGrey, else RGB. Non-finite values take the colour of the range's
// low end.
Image colorize(const Eigen::MatrixXd& field, const ScalarImageOptions& options = {});
// write_png(path, colorize(field, options)).
void write_scalar_png(const std::filesystem::path& path, const Eigen::MatrixXd& field,
                      const ScalarImageOptions& options = {});

}  // namespace nfield::io
