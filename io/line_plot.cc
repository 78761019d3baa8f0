// SPDX-License-Identifier: MIT
#include "io/line_plot.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace nfield::io {
namespace {

struct Canvas {
  Image& image;
  int top, bottom;  // rows of the panel, inclusive
  int left, right;  // columns of the panel, inclusive

  void put(int row, int column, const std::array<float, 3>& rgb) const {
    if (row < top || row > bottom || column < left || column > right) return;
    for (int c = 0; c < 3; ++c) image.pixels(static_cast<Eigen::Index>(row) * image.width + column, c) = rgb[c];
  }
  // A segment between two pixel positions, sampled at every pixel step.
  void line(double r0, double c0, double r1, double c1, const std::array<float, 3>& rgb) const {
    const int steps = std::max(1, static_cast<int>(std::ceil(std::max(std::abs(r1 - r0), std::abs(c1 - c0)))));
    for (int s = 0; s <= steps; ++s) {
      const double t = static_cast<double>(s) / steps;
      put(static_cast<int>(std::lround(r0 + t * (r1 - r0))), static_cast<int>(std::lround(c0 + t * (c1 - c0))), rgb);
    }
  }
};

}  // namespace

Image plot_curves(const std::vector<PlotPanel>& panels, int width, int height) {
  if (panels.empty()) throw std::invalid_argument("plot_curves: no panels");
  const int panel_height = height / static_cast<int>(panels.size());
  if (width < 32 || panel_height < 32)
    throw std::invalid_argument("plot_curves: " + std::to_string(width) + " x " + std::to_string(height) +
                                " is too small for " + std::to_string(panels.size()) + " panels");
  Image image{width, height, 3, Eigen::MatrixXf::Ones(static_cast<Eigen::Index>(width) * height, 3)};
  const std::array<float, 3> grey{0.6f, 0.6f, 0.6f};
  const int margin = 8;

  for (size_t p = 0; p < panels.size(); ++p) {
    const Canvas canvas{image, static_cast<int>(p) * panel_height + margin,
                        static_cast<int>(p + 1) * panel_height - margin, margin, width - 1 - margin};
    double x_low = std::numeric_limits<double>::infinity(), x_high = -x_low, y_low = x_low, y_high = -x_low;
    for (const Curve& curve : panels[p].curves) {
      if (curve.x.size() != curve.y.size())
        throw std::invalid_argument("plot_curves: a curve has " + std::to_string(curve.x.size()) + " x and " +
                                    std::to_string(curve.y.size()) + " y values");
      for (Eigen::Index i = 0; i < curve.x.size(); ++i) {
        if (!std::isfinite(curve.x(i)) || !std::isfinite(curve.y(i))) continue;
        x_low = std::min(x_low, curve.x(i));
        x_high = std::max(x_high, curve.x(i));
        y_low = std::min(y_low, curve.y(i));
        y_high = std::max(y_high, curve.y(i));
      }
    }
    if (!(x_low <= x_high)) throw std::invalid_argument("plot_curves: panel " + std::to_string(p) + " has no finite point");
    if (x_high == x_low) x_high = x_low + 1;
    const double pad = 0.05 * std::max(y_high - y_low, 1e-12 * std::max(1.0, std::abs(y_high)));
    y_low -= pad;
    y_high += pad;
    const auto column = [&](double x) { return canvas.left + (x - x_low) / (x_high - x_low) * (canvas.right - canvas.left); };
    const auto row = [&](double y) { return canvas.bottom - (y - y_low) / (y_high - y_low) * (canvas.bottom - canvas.top); };

    canvas.line(canvas.top, canvas.left, canvas.top, canvas.right, grey);
    canvas.line(canvas.bottom, canvas.left, canvas.bottom, canvas.right, grey);
    canvas.line(canvas.top, canvas.left, canvas.bottom, canvas.left, grey);
    canvas.line(canvas.top, canvas.right, canvas.bottom, canvas.right, grey);
    if (y_low < 0 && y_high > 0) canvas.line(row(0), canvas.left, row(0), canvas.right, grey);

    for (const Curve& curve : panels[p].curves) {
      // Consecutive points are joined; many points in one pixel column fill the range of
      // their values there, so a dense signal shows its envelope.
      double previous_row = std::numeric_limits<double>::quiet_NaN(), previous_column = 0;
      for (Eigen::Index i = 0; i < curve.x.size(); ++i) {
        if (!std::isfinite(curve.x(i)) || !std::isfinite(curve.y(i))) {
          previous_row = std::numeric_limits<double>::quiet_NaN();
          continue;
        }
        const double r = row(curve.y(i)), c = column(curve.x(i));
        if (std::isnan(previous_row)) canvas.put(static_cast<int>(std::lround(r)), static_cast<int>(std::lround(c)), curve.rgb);
        else canvas.line(previous_row, previous_column, r, c, curve.rgb);
        previous_row = r;
        previous_column = c;
      }
    }
  }
  return image;
}

}  // namespace nfield::io
