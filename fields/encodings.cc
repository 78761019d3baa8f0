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
    r.add("cusp", 3);
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

// |z|, with derivative sign(z) (0 at z = 0) and no higher ones.
template <typename Scalar>
class Abs final : public autodiff::ElementwiseFunction<Scalar> {
 public:
  void derivatives(const Eigen::Ref<const autodiff::Matrix<Scalar>>& z, int max_order,
                   std::vector<autodiff::Matrix<Scalar>>& tables) const override {
    tables.resize(max_order + 1);
    for (auto& table : tables) table.resize(z.rows(), z.cols());
    tables[0] = z.cwiseAbs();
    if (max_order >= 1)
      tables[1] = z.unaryExpr([](Scalar v) { return Scalar((v > 0) - (v < 0)); });
    for (int m = 2; m <= max_order; ++m) tables[m].setZero();
  }
};

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
  if (kind == "cusp" && at.empty())
    throw std::invalid_argument("encoding.at = []: needs at least one plane");
  if (kind == "cusp")
    for (double c : at)
      if (!std::isfinite(c))
        throw std::invalid_argument("encoding.at = " + std::to_string(c) + ": must be finite");
  if (kind == "cusp" && axis < 0)
    throw std::invalid_argument("encoding.axis = " + std::to_string(axis) + ": must be >= 0");
  if (from_stage < 0)
    throw std::invalid_argument("encoding.from_stage = " + std::to_string(from_stage) +
                                ": must be >= 0");
  if (from_stage > 0 && kind != "cusp")
    throw std::invalid_argument("encoding.from_stage = " + std::to_string(from_stage) +
                                ": only cusp features can enter at a later stage");
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
  if (kind == "cusp") {
    if (options.axis >= input_dim)
      throw std::invalid_argument("encoding.axis = " + std::to_string(options.axis) +
                                  ": must be < the input dimension " + std::to_string(input_dim));
    Eigen::MatrixXd b = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(options.at.size()), input_dim);
    b.col(options.axis).setOnes();
    return b;
  }
  return Eigen::MatrixXd(0, input_dim);
}

std::vector<std::string> encoding_names() { return encodings().names(); }

template <typename Scalar>
FeatureEncoding<Scalar>::FeatureEncoding(const Eigen::MatrixXd& weights,
                                         const Eigen::VectorXd& offsets,
                                         std::unique_ptr<autodiff::ElementwiseFunction<Scalar>> function,
                                         bool include_input)
    : weights_(weights.cast<Scalar>()),
      offsets_(offsets.transpose().cast<Scalar>()),
      function_(std::move(function)),
      include_input_(include_input) {
  if (offsets.size() != weights.rows())
    throw std::logic_error("FeatureEncoding: one offset per row of the weights expected");
}

// saved = [z streams (one matrix), derivative tables …]
template <typename Scalar>
void FeatureEncoding<Scalar>::forward(const autodiff::StreamLayout& layout, const Scalar*,
                                      const autodiff::Streams<Scalar>& in,
                                      autodiff::Streams<Scalar>& out,
                                      autodiff::SavedTensors<Scalar>* saved) const {
  const Eigen::Index d = include_input_ ? in.width() : 0;
  if (!features_on_) {
    out.resize(in.points, in.count, d + weights_.rows());
    if (d > 0) out.data.leftCols(d) = in.data;
    out.data.rightCols(weights_.rows()).setZero();
    if (saved) saved->clear();
    return;
  }
  thread_local autodiff::Streams<Scalar> z, y;
  thread_local std::vector<autodiff::Matrix<Scalar>> tables;
  z.resize(in.points, in.count, weights_.rows());
  z.data.noalias() = in.data * weights_.transpose();
  z.stream(0).rowwise() += offsets_.row(0);
  const int order = layout.forward_order() + (saved ? 1 : 0);
  function_->derivatives(z.stream(0), order, tables);
  autodiff::elementwise_forward(layout, tables, z, y);
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
void FeatureEncoding<Scalar>::backward(const autodiff::StreamLayout& layout, const Scalar*,
                                       const autodiff::Streams<Scalar>& in,
                                       const autodiff::SavedTensors<Scalar>& saved,
                                       autodiff::Streams<Scalar>& out_adjoint, Scalar*,
                                       autodiff::Streams<Scalar>* in_adjoint) const {
  if (!in_adjoint) return;
  const Eigen::Index d = include_input_ ? in.width() : 0;
  if (!features_on_) {
    in_adjoint->resize(in.points, in.count, in.width());
    if (d > 0)
      in_adjoint->data = out_adjoint.data.leftCols(d);
    else
      in_adjoint->data.setZero();
    return;
  }
  thread_local autodiff::Streams<Scalar> z, y_adjoint, z_adjoint;
  thread_local std::vector<autodiff::Matrix<Scalar>> tables;
  z.points = in.points;
  z.count = in.count;
  z.data = saved[0];
  tables.assign(saved.begin() + 1, saved.end());
  y_adjoint.resize(in.points, in.count, weights_.rows());
  y_adjoint.data = out_adjoint.data.rightCols(weights_.rows());
  autodiff::elementwise_backward(layout, tables, z, y_adjoint, z_adjoint);
  in_adjoint->resize(in.points, in.count, in.width());
  in_adjoint->data.noalias() = z_adjoint.data * weights_;
  if (d > 0) in_adjoint->data += out_adjoint.data.leftCols(d);
}

template <typename Scalar>
std::unique_ptr<autodiff::Module<Scalar>> make_encoding(const EncodingOptions& options,
                                                        int input_dim) {
  const Eigen::MatrixXd b = encoding_matrix(options, input_dim);
  const std::string kind = Registry<int>::lower(options.type);
  if (kind == "identity") return nullptr;
  if (kind == "cusp")
    return std::make_unique<FeatureEncoding<Scalar>>(
        b, -Eigen::Map<const Eigen::VectorXd>(options.at.data(), b.rows()),
        std::make_unique<Abs<Scalar>>(), true);
  const Eigen::Index m = b.rows();
  Eigen::MatrixXd doubled(2 * m, input_dim);
  doubled << b, b;
  Eigen::VectorXd phase(2 * m);
  phase << Eigen::VectorXd::Zero(m), Eigen::VectorXd::Constant(m, std::numbers::pi / 2);
  return std::make_unique<FeatureEncoding<Scalar>>(
      doubled, phase, make_activation<Scalar>({"sine", 1.0}),
      kind == "positional" && options.include_input);
}

template class FeatureEncoding<float>;
template class FeatureEncoding<double>;
template std::unique_ptr<autodiff::Module<float>> make_encoding<float>(const EncodingOptions&, int);
template std::unique_ptr<autodiff::Module<double>> make_encoding<double>(const EncodingOptions&, int);

}  // namespace nfield::fields
