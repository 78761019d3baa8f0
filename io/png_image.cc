// SPDX-License-Identifier: MIT
#include "io/png_image.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <tuple>

#include <vtkDataArray.h>
#include <vtkImageData.h>
#include <vtkNew.h>
#include <vtkPNGReader.h>
#include <vtkPNGWriter.h>
#include <vtkPointData.h>
#include <vtkUnsignedCharArray.h>

#include "io/atomic_write.h"
#include "io/vtk_convert.h"
#include "io/vtk_errors.h"

namespace nfield::io {
namespace fs = std::filesystem;

Image read_png(const fs::path& path) {
  const auto fail = [&](const std::string& why) {
    return std::runtime_error("read_png: '" + path.string() + "': " + why);
  };
  if (!fs::is_regular_file(path)) throw fail("no such file");
  vtkNew<vtkPNGReader> reader;
  VtkErrorCatcher errors(reader);
  if (!reader->CanReadFile(path.c_str())) throw fail("not a PNG file");
  reader->SetFileName(path.c_str());
  reader->Update();
  vtkImageData* data = reader->GetOutput();
  vtkDataArray* scalars = data ? data->GetPointData()->GetScalars() : nullptr;
  if (errors.failed() || !scalars) throw fail("cannot decode: " + errors.message());
  int dims[3];
  data->GetDimensions(dims);
  Image image{dims[0], dims[1], scalars->GetNumberOfComponents(), {}};
  // VTK's row 0 is the bottom row of the picture.
  const Eigen::MatrixXd values = from_vtk_array(scalars) / scalars->GetDataTypeMax();
  image.pixels.resize(Eigen::Index{image.width} * image.height, image.channels);
  for (int r = 0; r < image.height; ++r)
    image.pixels.middleRows(Eigen::Index{r} * image.width, image.width) =
        values.middleRows(Eigen::Index{image.height - 1 - r} * image.width, image.width)
            .cast<float>();
  return image;
}

void write_png(const fs::path& path, const Image& image) {
  if (image.width < 1 || image.height < 1 || image.channels < 1 || image.channels > 4 ||
      image.pixels.rows() != Eigen::Index{image.width} * image.height ||
      image.pixels.cols() != image.channels)
    throw std::invalid_argument("write_png: '" + path.string() + "': the image is " +
                                std::to_string(image.width) + "x" + std::to_string(image.height) +
                                "x" + std::to_string(image.channels) + " but its pixels are " +
                                std::to_string(image.pixels.rows()) + "x" +
                                std::to_string(image.pixels.cols()) + " (1 to 4 channels)");
  vtkNew<vtkImageData> data;
  data->SetDimensions(image.width, image.height, 1);
  vtkNew<vtkUnsignedCharArray> bytes;
  bytes->SetNumberOfComponents(image.channels);
  bytes->SetNumberOfTuples(Eigen::Index{image.width} * image.height);
  for (int r = 0; r < image.height; ++r)
    for (int c = 0; c < image.width; ++c)
      for (int k = 0; k < image.channels; ++k) {
        const float v = image.pixels(Eigen::Index{r} * image.width + c, k);
        const float clamped = std::isnan(v) ? 0.f : std::clamp(v, 0.f, 1.f);
        bytes->SetTypedComponent(Eigen::Index{image.height - 1 - r} * image.width + c, k,
                                 static_cast<unsigned char>(std::lround(clamped * 255.f)));
      }
  data->GetPointData()->SetScalars(bytes);
  write_atomically(path, [&](const fs::path& tmp) {
    vtkNew<vtkPNGWriter> writer;
    VtkErrorCatcher errors(writer);
    writer->SetInputData(data);
    writer->SetFileName(tmp.c_str());
    writer->Write();
    if (errors.failed() || writer->GetErrorCode())
      throw std::runtime_error("vtkPNGWriter: " + errors.message());
  });
}

namespace {
using Rgb = std::array<float, 3>;
// Samples of matplotlib's viridis at 0, 1/8, ..., 1.
constexpr Rgb kViridis[] = {
    {0.267f, 0.004f, 0.329f}, {0.278f, 0.176f, 0.482f}, {0.231f, 0.322f, 0.545f},
    {0.173f, 0.447f, 0.557f}, {0.129f, 0.569f, 0.549f}, {0.157f, 0.682f, 0.502f},
    {0.369f, 0.788f, 0.384f}, {0.678f, 0.863f, 0.188f}, {0.992f, 0.906f, 0.145f}};
// Moreland's cool-warm at 0, 1/4, ..., 1 (white-ish at the middle).
constexpr Rgb kCoolWarm[] = {{0.230f, 0.299f, 0.754f},
                             {0.552f, 0.690f, 0.996f},
                             {0.865f, 0.865f, 0.865f},
                             {0.958f, 0.604f, 0.483f},
                             {0.706f, 0.016f, 0.150f}};

// Piecewise-linear lookup of t in [0, 1].
template <std::size_t N>
Rgb lookup(const Rgb (&table)[N], double t) {
  const double x = t * (N - 1);
  const std::size_t i = std::min<std::size_t>(static_cast<std::size_t>(x), N - 2);
  const float w = static_cast<float>(x - i);
  Rgb out;
  for (int k = 0; k < 3; ++k) out[k] = (1 - w) * table[i][k] + w * table[i + 1][k];
  return out;
}
}  // namespace

Image central_crop(const Image& image, int width, int height) {
  if (width < 1 || height < 1)
    throw std::invalid_argument("central_crop: a crop of " + std::to_string(width) + " x " + std::to_string(height));
  width = std::min(width, image.width);
  height = std::min(height, image.height);
  const int x0 = (image.width - width) / 2, y0 = (image.height - height) / 2;
  Image out{width, height, image.channels, Eigen::MatrixXf(Eigen::Index{width} * height, image.channels)};
  for (int r = 0; r < height; ++r)
    out.pixels.middleRows(Eigen::Index{r} * width, width) =
        image.pixels.middleRows(Eigen::Index{y0 + r} * image.width + x0, width);
  return out;
}

Image box_downsample(const Image& image, int factor) {
  if (factor < 1 || factor > image.width || factor > image.height)
    throw std::invalid_argument("box_downsample: a factor of " + std::to_string(factor) + " for a " +
                                std::to_string(image.width) + " x " + std::to_string(image.height) + " picture");
  const int width = image.width / factor, height = image.height / factor;
  Image out{width, height, image.channels, Eigen::MatrixXf::Zero(Eigen::Index{width} * height, image.channels)};
  for (int r = 0; r < height * factor; ++r)
    for (int c = 0; c < width * factor; ++c)
      out.pixels.row(Eigen::Index{r / factor} * width + c / factor) += image.pixels.row(Eigen::Index{r} * image.width + c);
  out.pixels /= static_cast<float>(factor * factor);
  return out;
}

Image with_channels(const Image& image, int channels) {
  if (channels != 1 && channels != 3)
    throw std::invalid_argument("with_channels: " + std::to_string(channels) + " channels (expected 1 or 3)");
  const int colour = image.channels >= 3 ? 3 : 1;
  Image out{image.width, image.height, channels, Eigen::MatrixXf(image.pixels.rows(), channels)};
  if (channels == 1)
    out.pixels.col(0) = image.pixels.leftCols(colour).rowwise().mean();
  else
    for (int k = 0; k < 3; ++k) out.pixels.col(k) = image.pixels.col(colour == 3 ? k : 0);
  return out;
}

Image colorize(const Eigen::MatrixXd& field, const ScalarImageOptions& options) {
  double lo, hi;
  if (options.range) {
    std::tie(lo, hi) = *options.range;
    if (!(hi > lo)) throw std::invalid_argument("colorize: the range needs low < high");
  } else {
    lo = std::numeric_limits<double>::infinity();
    hi = -lo;
    for (double v : field.reshaped())
      if (std::isfinite(v)) {
        lo = std::min(lo, v);
        hi = std::max(hi, v);
      }
    if (lo > hi) std::tie(lo, hi) = std::pair(0.0, 1.0);  // nothing finite
    if (options.colormap == Colormap::kDiverging) {
      hi = std::max(std::abs(lo), std::abs(hi));
      lo = -hi;
    }
  }
  const int channels = options.colormap == Colormap::kGrey ? 1 : 3;
  Image image{static_cast<int>(field.cols()), static_cast<int>(field.rows()), channels, {}};
  image.pixels.resize(field.size(), channels);
  for (Eigen::Index r = 0; r < field.rows(); ++r)
    for (Eigen::Index c = 0; c < field.cols(); ++c) {
      const double v = field(r, c);
      const double t = !std::isfinite(v) ? 0.0
                       : hi > lo         ? std::clamp((v - lo) / (hi - lo), 0.0, 1.0)
                                         : 0.5;
      const Eigen::Index p = r * field.cols() + c;
      if (options.colormap == Colormap::kGrey) {
        image.pixels(p, 0) = static_cast<float>(t);
      } else {
        const Rgb rgb =
            options.colormap == Colormap::kViridis ? lookup(kViridis, t) : lookup(kCoolWarm, t);
        for (int k = 0; k < 3; ++k) image.pixels(p, k) = rgb[k];
      }
    }
  return image;
}

void write_scalar_png(const fs::path& path, const Eigen::MatrixXd& field,
                      const ScalarImageOptions& options) {
  write_png(path, colorize(field, options));
}

}  // namespace nfield::io
