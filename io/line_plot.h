// SPDX-License-Identifier: MIT
//
// Curves y(x) drawn into an image, for a quick look at 1-D results (no text: the caller's
// documentation names the colours). Panels are stacked top to bottom, each with its own y
// range (the curves' finite extent, widened by 5 %), a grey frame and a grey line at y = 0
// when 0 is in range. Consecutive points are joined by segments, so a curve with more points
// than the panel has pixel columns shows its envelope (a dense signal such as audio).
#pragma once

#include <array>
#include <vector>

#include <Eigen/Core>

#include "io/png_image.h"

namespace nfield::io {

struct Curve {
  Eigen::VectorXd x, y;            // the same length, x increasing
  std::array<float, 3> rgb{0, 0, 0};  // in [0, 1]
};

struct PlotPanel {
  std::vector<Curve> curves;
};

// An RGB image of width × height. Throws std::invalid_argument when a curve's x and y
// differ in length, a panel has no finite value, or the size is below 32 × 32 per panel.
Image plot_curves(const std::vector<PlotPanel>& panels, int width, int height);

}  // namespace nfield::io
