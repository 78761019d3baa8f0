// SPDX-License-Identifier: MIT
#include "fields/encodings.h"

#include <cmath>
#include <numbers>
#include <random>
#include <stdexcept>

#include "autodiff/elementwise.h"
#include "fields/activations.h"
#include "io/registry.h"

namespace nfield::fields {
namespace {

const Registry<int>& encodings() {
  static const Registry<int> registry = [] {
    Registry<int> r("encoding");
    r.add("identity", 0);
    r.add("positional", 1);
    r.add("fourier", 2);
    return r;
  }();
  return registry;
}

// Standard normal draws that do not depend on the standard library's distributions.
double normal(std::mt19937_64& rng) {
  const double u1 = (static_cast<double>(rng() >> 11) + 0.5) * 0x1.0p-53;
  const double u2 = static_cast<double>(rng() >> 11) * 0x1.0p-53;
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * std::numbers::pi * u2);
}

}  // namespace

void EncodingOptions::validate() const {
  const std::string kind = Registry<int>::lower(type);
  encodings().at(kind);
  if (kind == "positional" && (frequencies < 1 || frequencies > 24))
    throw std::invalid_argument("encoding.frequencies = " + std::to_string(frequencies) +
                                ": must be in [1, 24]");
  if (kind == "fourier" && features < 1)
    throw std::invalid_argument("encoding.features = " + std::to_string(features) +
                                ": must be >= 1");
  if (kind == "fourier" && !(scale > 0))
    throw std::invalid_argument("encoding.scale = " + std::to_string(scale) + ": must be > 0");
}

Eigen::MatrixXd encoding_matrix(const EncodingOptions& options, int input_dim) {
  options.validate();
  const std::string kind = Registry<int>::lower(options.type);
  if (kind == "positional") {
    Eigen::MatrixXd b = Eigen::MatrixXd::Zero(options.frequencies * input_dim, input_dim);
    for (int l = 0; l < options.frequencies; ++l)
      for (int i = 0; i < input_dim; ++i)
        b(l * input_dim + i, i) = std::ldexp(std::numbers::pi, l);
    return b;
  }
  if (kind == "fourier") {
    std::mt19937_64 rng(options.seed);
    Eigen::MatrixXd b(options.features, input_dim);
    for (Eigen::Index r = 0; r < b.rows(); ++r)
      for (Eigen::Index c = 0; c < b.cols(); ++c)
        b(r, c) = 2.0 * std::numbers::pi * options.scale * normal(rng);
    return b;
  }
  return Eigen::MatrixXd(0, input_dim);
}

std::vector<std::string> encoding_names() { return encodings().names(); }

template <typename Scalar>
SinusoidalEncoding<Scalar>::SinusoidalEncoding(Eigen::MatrixXd frequencies, bool include_input)
    : frequencies_(std::move(frequencies)), include_input_(include_input) {
  const Eigen::Index m = frequencies_.rows();
  doubled_.resize(2 * m, frequencies_.cols());
  doubled_ << frequencies_.cast<Scalar>(), frequencies_.cast<Scalar>();
  phase_.resize(1, 2 * m);
  phase_.leftCols(m).setZero();
  phase_.rightCols(m).setConstant(static_cast<Scalar>(std::numbers::pi / 2));
}

// saved = [z streams (one matrix), derivative tables …]
template <typename Scalar>
void SinusoidalEncoding<Scalar>::forward(const autodiff::StreamLayout& layout, const Scalar*,
                                         const autodiff::Streams<Scalar>& in,
                                         autodiff::Streams<Scalar>& out,
                                         autodiff::SavedTensors<Scalar>* saved) const {
  thread_local autodiff::Streams<Scalar> z, y;
  thread_local std::vector<autodiff::Matrix<Scalar>> tables;
  static const auto sine = make_activation<Scalar>({"sine", 1.0});
  z.resize(in.points, in.count, doubled_.rows());
  z.data.noalias() = in.data * doubled_.transpose();
  z.stream(0).rowwise() += phase_.row(0);
  const int order = layout.forward_order() + (saved ? 1 : 0);
  sine->derivatives(z.stream(0), order, tables);
  autodiff::elementwise_forward(layout, tables, z, y);
  const Eigen::Index d = include_input_ ? in.width() : 0;
  out.resize(in.points, in.count, d + y.width());
  if (d > 0) out.data.leftCols(d) = in.data;
  out.data.rightCols(y.width()) = y.data;
  if (saved) {
    saved->resize(1 + tables.size());
    (*saved)[0] = z.data;
    for (size_t m = 0; m < tables.size(); ++m) (*saved)[1 + m] = tables[m];
  }
}

template <typename Scalar>
void SinusoidalEncoding<Scalar>::backward(const autodiff::StreamLayout& layout, const Scalar*,
                                          const autodiff::Streams<Scalar>& in,
                                          const autodiff::SavedTensors<Scalar>& saved,
                                          autodiff::Streams<Scalar>& out_adjoint, Scalar*,
                                          autodiff::Streams<Scalar>* in_adjoint) const {
  if (!in_adjoint) return;
  thread_local autodiff::Streams<Scalar> z, y_adjoint, z_adjoint;
  thread_local std::vector<autodiff::Matrix<Scalar>> tables;
  z.points = in.points;
  z.count = in.count;
  z.data = saved[0];
  tables.assign(saved.begin() + 1, saved.end());
  const Eigen::Index d = include_input_ ? in.width() : 0;
  y_adjoint.resize(in.points, in.count, doubled_.rows());
  y_adjoint.data = out_adjoint.data.rightCols(doubled_.rows());
  autodiff::elementwise_backward(layout, tables, z, y_adjoint, z_adjoint);
  in_adjoint->resize(in.points, in.count, in.width());
  in_adjoint->data.noalias() = z_adjoint.data * doubled_;
  if (d > 0) in_adjoint->data += out_adjoint.data.leftCols(d);
}

template class SinusoidalEncoding<float>;
template class SinusoidalEncoding<double>;

}  // namespace nfield::fields
