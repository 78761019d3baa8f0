// SPDX-License-Identifier: MIT
#include "solvers/geometry/spline_distance.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace nfield::solvers::geometry {

QuinticWeights quintic_weights(double t) {
  // a[q][j] = M_q(t + j), the cardinal B-spline of degree q (support [0, q + 1]) by the
  // recursion M_q(x) = (x M_{q−1}(x) + (q + 1 − x) M_{q−1}(x − 1)) / q.
  double a[6][7] = {};
  a[0][0] = 1;
  for (int q = 1; q <= 5; ++q)
    for (int j = 0; j <= q; ++j) {
      const double left = j < q ? a[q - 1][j] : 0, right = j > 0 ? a[q - 1][j - 1] : 0;
      a[q][j] = ((t + j) * left + (q + 1 - t - j) * right) / q;
    }
  const auto at = [&](int q, int j) { return j >= 0 && j <= q ? a[q][j] : 0.0; };
  QuinticWeights r;
  for (int k = 0; k < 6; ++k) {
    const int j = 5 - k;  // B(t + 2 − k) = M_5(t + 5 − k)
    r.w[static_cast<size_t>(k)] = at(5, j);
    r.d1[static_cast<size_t>(k)] = at(4, j) - at(4, j - 1);
    r.d2[static_cast<size_t>(k)] = at(3, j) - 2 * at(3, j - 1) + at(3, j - 2);
  }
  return r;
}

namespace {
// v ← S v along one axis of an n[0]×n[1]×n[2] array (x fastest): the quintic spline's values
// at the nodes, (1, 26, 66, 26, 1)/120, the border node repeated beyond the ends.
void smooth_axis(std::vector<double>& v, const std::array<int, 3>& n, int axis) {
  static constexpr double kTaps[5] = {1.0 / 120, 26.0 / 120, 66.0 / 120, 26.0 / 120, 1.0 / 120};
  const size_t stride = axis == 0 ? 1 : axis == 1 ? static_cast<size_t>(n[0]) : static_cast<size_t>(n[0]) * n[1];
  const int len = n[static_cast<size_t>(axis)];
  std::vector<double> line(static_cast<size_t>(len));
  const size_t total = v.size();
  for (size_t start = 0; start < total; ++start) {
    if ((start / stride) % static_cast<size_t>(len) != 0) continue;  // not the first node of a line
    for (int i = 0; i < len; ++i) line[static_cast<size_t>(i)] = v[start + static_cast<size_t>(i) * stride];
    for (int i = 0; i < len; ++i) {
      double s = 0;
      for (int k = -2; k <= 2; ++k) s += kTaps[k + 2] * line[static_cast<size_t>(std::clamp(i + k, 0, len - 1))];
      v[start + static_cast<size_t>(i) * stride] = s;
    }
  }
}
}  // namespace

SplineDistance::SplineDistance(const Bounds& box, int cells, const Sampler& sample) {
  if (cells < 4) throw std::invalid_argument("a spline distance needs at least 4 cells, got " + std::to_string(cells));
  const Vec3 extent = box.upper - box.lower;
  if (!(extent.maxCoeff() > 0)) throw std::invalid_argument("a spline distance needs a box of positive size");
  h_ = extent.maxCoeff() / cells;
  origin_ = box.lower - Vec3::Constant(4 * h_);
  for (int a = 0; a < 3; ++a) n_[static_cast<size_t>(a)] = static_cast<int>(std::ceil(extent(a) / h_ - 1e-9)) + 9;
  const size_t total = static_cast<size_t>(n_[0]) * n_[1] * n_[2];
  Eigen::MatrixXd nodes(static_cast<Eigen::Index>(total), 3);
  for (int k = 0; k < n_[2]; ++k)
    for (int j = 0; j < n_[1]; ++j)
      for (int i = 0; i < n_[0]; ++i)
        nodes.row(static_cast<Eigen::Index>((static_cast<size_t>(k) * n_[1] + j) * n_[0] + i)) =
            (origin_ + h_ * Vec3(i, j, k)).transpose();
  const Eigen::VectorXd f = sample(nodes);
  if (static_cast<size_t>(f.size()) != total) throw std::logic_error("SplineDistance: the sampler returned the wrong count");
  std::vector<double> s(f.data(), f.data() + total);
  for (int a = 0; a < 3; ++a) smooth_axis(s, n_, a);
  coefficients_.resize(total);
  for (size_t i = 0; i < total; ++i) coefficients_[i] = 2 * f(static_cast<Eigen::Index>(i)) - s[i];
}

Scalar2 SplineDistance::operator()(const Vec3& x) const {
  int i0[3];
  QuinticWeights w[3];
  for (int a = 0; a < 3; ++a) {
    const double hi = n_[static_cast<size_t>(a)] - 4 - 1e-9;
    const double u = std::clamp((x(a) - origin_(a)) / h_, 2.0, hi);
    i0[a] = static_cast<int>(std::floor(u));
    w[a] = quintic_weights(u - i0[a]);
  }
  // Contract z, then y, then x; Y<p><q>: p derivatives in y, q in z.
  double v = 0, gx = 0, gy = 0, gz = 0, hxx = 0, hyy = 0, hzz = 0, hxy = 0, hxz = 0, hyz = 0;
  for (int a = 0; a < 6; ++a) {
    double y00 = 0, y10 = 0, y20 = 0, y01 = 0, y11 = 0, y02 = 0;
    for (int b = 0; b < 6; ++b) {
      double z0 = 0, z1 = 0, z2 = 0;
      for (int k = 0; k < 6; ++k) {
        const double ck = c(i0[0] - 2 + a, i0[1] - 2 + b, i0[2] - 2 + k);
        z0 += ck * w[2].w[static_cast<size_t>(k)];
        z1 += ck * w[2].d1[static_cast<size_t>(k)];
        z2 += ck * w[2].d2[static_cast<size_t>(k)];
      }
      const double wy = w[1].w[static_cast<size_t>(b)], dy = w[1].d1[static_cast<size_t>(b)],
                   ddy = w[1].d2[static_cast<size_t>(b)];
      y00 += wy * z0, y10 += dy * z0, y20 += ddy * z0, y01 += wy * z1, y11 += dy * z1, y02 += wy * z2;
    }
    const double wx = w[0].w[static_cast<size_t>(a)], dx = w[0].d1[static_cast<size_t>(a)],
                 ddx = w[0].d2[static_cast<size_t>(a)];
    v += wx * y00, gx += dx * y00, gy += wx * y10, gz += wx * y01;
    hxx += ddx * y00, hyy += wx * y20, hzz += wx * y02, hxy += dx * y10, hxz += dx * y01, hyz += wx * y11;
  }
  Scalar2 r(v);
  r.g = Vec3(gx, gy, gz) / h_;
  r.h << hxx, hxy, hxz, hxy, hyy, hyz, hxz, hyz, hzz;
  r.h /= h_ * h_;
  return r;
}

}  // namespace nfield::solvers::geometry
