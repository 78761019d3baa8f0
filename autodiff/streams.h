// SPDX-License-Identifier: MIT
//
// Derivative streams: the data every layer of a field passes on.
//
// For a batch of N points x ∈ R^d, each quantity inside a network is carried as S streams,
// each an N × width matrix:
//
//   value       a⁰                          1 stream
//   tangents    a⁽ⁱ⁾ = ∂a/∂vᵢ               one per direction vᵢ (columns of `tangents`)
//   operators   a^[C] = Σᵢⱼ Cᵢⱼ ∂²a/∂vᵢ∂vⱼ   one per symmetric T × T matrix C over the tangents
//   Taylor      a_{p,k} = (1/k!) dᵏ/dτᵏ a(x + τ w_p) at τ = 0, k = 1..K, one series per
//               direction w_p (columns of `taylor_directions`)
//
// With the coordinate axes as tangents, C = I gives the Laplacian, C = diag(−c², …, 1) the
// wave operator over (x, …, t), C = e_x e_xᵀ a single ∂xx. Orders above two (Δ², u_xxx) come
// from Taylor series; mixed partials by polarization:
// e.g. u_xxyy = (D⁴₍ₓ₊ᵧ₎ + D⁴₍ₓ₋ᵧ₎ − 2D⁴ₓ − 2D⁴ᵧ)/12 with D⁴_w = 4! a_{w,4}.
// An isotropic operator needs fewer directions than polarization: in 2D the mean of D⁴ over
// three directions 60° apart is (3/8)Δ² exactly (equally spaced angles integrate the
// harmonics 2 and 4 of cos⁴ exactly), so Δ²u = (64/3) Σₚ a_{p,4} from 1 + 3·4 = 13 streams
// instead of the 17 of the four axis and diagonal directions (biharmonic_directions_2d).
//
// Memory layout: all streams of a layer are stacked into one (S·N) × width column-major
// matrix; stream s owns rows [s·N, (s+1)·N). A linear layer is then one matrix product over
// all streams (z = a Wᵀ, the bias added to the value rows only).
#pragma once

#include <Eigen/Core>
#include <vector>

namespace nfield::autodiff {

template <typename Scalar>
using Matrix = Eigen::Matrix<Scalar, Eigen::Dynamic, Eigen::Dynamic>;
template <typename Scalar>
using Vector = Eigen::Matrix<Scalar, Eigen::Dynamic, 1>;

// What derivatives a pass computes. Defaults: values only.
struct StreamSpec {
  int input_dim = 0;
  Eigen::MatrixXd tangents;                // input_dim × T, the directions vᵢ
  std::vector<Eigen::MatrixXd> operators;  // each T × T and symmetric
  Eigen::MatrixXd taylor_directions;       // input_dim × D, the directions w_p
  int taylor_order = 0;                    // K; 0 when D = 0

  static StreamSpec values(int input_dim);
  // Tangents along the coordinate axes.
  static StreamSpec gradient(int input_dim);
  // Gradient plus the Laplacian stream (C = I).
  static StreamSpec laplacian(int input_dim);

  // Appends an operator stream tr(C ∇²·) over the current tangents; returns its index.
  int add_operator(const Eigen::MatrixXd& coefficients);
  // Sets Taylor series of order `order` along each column of `directions`.
  void set_taylor(const Eigen::MatrixXd& directions, int order);

  // Throws std::invalid_argument naming the field, its value and the rule it breaks.
  void validate() const;
};

// One term of Σᵢⱼ Cᵢⱼ zᵢ zⱼ with i ≤ j; the coefficient of an off-diagonal pair is already
// Cᵢⱼ + Cⱼᵢ, so each unordered pair is visited once and zero entries never.
struct OperatorTerm {
  int i = 0;
  int j = 0;
  double coefficient = 0;
};

// Stream indices for a validated spec.
class StreamLayout {
 public:
  explicit StreamLayout(StreamSpec spec);

  const StreamSpec& spec() const { return spec_; }
  int input_dim() const { return spec_.input_dim; }
  int count() const { return 1 + tangents_ + operators_ + taylor_dirs_ * taylor_order_; }
  int tangents() const { return tangents_; }
  int operators() const { return operators_; }
  int taylor_dirs() const { return taylor_dirs_; }
  int taylor_order() const { return taylor_order_; }

  static constexpr int value() { return 0; }
  int tangent(int i) const { return 1 + i; }
  int op(int q) const { return 1 + tangents_ + q; }
  int taylor(int p, int k) const { return 1 + tangents_ + operators_ + p * taylor_order_ + k - 1; }
  const std::vector<OperatorTerm>& terms(int q) const { return terms_[q]; }

  // Highest derivative order of an elementwise function the forward pass evaluates.
  int forward_order() const;

 private:
  StreamSpec spec_;
  int tangents_ = 0, operators_ = 0, taylor_dirs_ = 0, taylor_order_ = 0;
  std::vector<std::vector<OperatorTerm>> terms_;
};

// Unit directions at 0°, 60° and 120° (2 × 3): with Taylor order ≥ 4 along them,
// Δ²u = kBiharmonic2dWeight · Σₚ a_{p,4} (see the top of this file).
Eigen::MatrixXd biharmonic_directions_2d();
inline constexpr double kBiharmonic2dWeight = 64.0 / 3.0;  // (8/9) · 4!

// The streams of one quantity for a block of points.
template <typename Scalar>
struct Streams {
  Eigen::Index points = 0;
  int count = 0;
  Matrix<Scalar> data;  // (count · points) × width

  void resize(Eigen::Index n_points, int n_streams, Eigen::Index width) {
    points = n_points;
    count = n_streams;
    data.resize(n_points * n_streams, width);
  }
  Eigen::Index width() const { return data.cols(); }
  auto stream(int s) { return data.middleRows(s * points, points); }
  auto stream(int s) const { return data.middleRows(s * points, points); }
  // The values: stream 0 in every layout (StreamLayout::value()).
  auto values() { return stream(StreamLayout::value()); }
  auto values() const { return stream(StreamLayout::value()); }
};

// Tangent directions that differ from point to point (a ray's direction along the ray):
// row n holds point n's T directions one after another, direction i in columns
// [i·d, (i+1)·d). They replace the spec's shared `tangents` in the input streams; operator
// streams stay defined over whichever tangents are seeded.
template <typename Scalar>
using PointTangents = Matrix<Scalar>;  // N × (d·T)

// The input streams of points x (N × d): a⁰ = x, a⁽ⁱ⁾ = vᵢ, a^[C] = 0, a_{p,1} = w_p and
// higher Taylor coefficients 0. With `point_tangents` (rows matching x), a⁽ⁱ⁾ of point n is
// its own direction i instead of the spec's.
template <typename Scalar>
void seed_input_streams(const StreamLayout& layout, const Eigen::Ref<const Matrix<Scalar>>& x,
                        Streams<Scalar>& out,
                        const Eigen::Ref<const Matrix<Scalar>>* point_tangents = nullptr);

}  // namespace nfield::autodiff
