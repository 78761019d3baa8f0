// SPDX-License-Identifier: MIT
#include "autodiff/streams.h"

#include <cmath>
#include <numbers>

#include <sstream>
#include <stdexcept>

namespace nfield::autodiff {
namespace {

[[noreturn]] void reject(const std::string& field, const std::string& value,
                         const std::string& rule) {
  throw std::invalid_argument("StreamSpec." + field + " = " + value + ": " + rule);
}

std::string shape(const Eigen::MatrixXd& m) {
  return std::to_string(m.rows()) + "x" + std::to_string(m.cols()) + " matrix";
}

}  // namespace

StreamSpec StreamSpec::values(int input_dim) {
  StreamSpec spec;
  spec.input_dim = input_dim;
  spec.tangents.resize(input_dim, 0);
  spec.taylor_directions.resize(input_dim, 0);
  return spec;
}

StreamSpec StreamSpec::gradient(int input_dim) {
  StreamSpec spec = values(input_dim);
  spec.tangents = Eigen::MatrixXd::Identity(input_dim, input_dim);
  return spec;
}

StreamSpec StreamSpec::laplacian(int input_dim) {
  StreamSpec spec = gradient(input_dim);
  spec.add_operator(Eigen::MatrixXd::Identity(input_dim, input_dim));
  return spec;
}

int StreamSpec::add_operator(const Eigen::MatrixXd& coefficients) {
  operators.push_back(coefficients);
  return static_cast<int>(operators.size()) - 1;
}

void StreamSpec::set_taylor(const Eigen::MatrixXd& directions, int order) {
  taylor_directions = directions;
  taylor_order = order;
}

void StreamSpec::validate() const {
  if (input_dim < 1) reject("input_dim", std::to_string(input_dim), "must be at least 1");
  if (tangents.size() > 0 && tangents.rows() != input_dim)
    reject("tangents", shape(tangents), "needs input_dim = " + std::to_string(input_dim) + " rows");
  const Eigen::Index t = tangents.cols();
  for (size_t q = 0; q < operators.size(); ++q) {
    const Eigen::MatrixXd& c = operators[q];
    const std::string name = "operators[" + std::to_string(q) + "]";
    if (c.rows() != t || c.cols() != t)
      reject(name, shape(c), "must be T x T with T = " + std::to_string(t) + " tangents");
    if (t > 0 && (c - c.transpose()).cwiseAbs().maxCoeff() > 1e-12 * (1 + c.cwiseAbs().maxCoeff()))
      reject(name, shape(c), "must be symmetric");
  }
  if (taylor_order < 0) reject("taylor_order", std::to_string(taylor_order), "must be >= 0");
  if (taylor_directions.cols() > 0) {
    if (taylor_directions.rows() != input_dim)
      reject("taylor_directions", shape(taylor_directions),
             "needs input_dim = " + std::to_string(input_dim) + " rows");
    if (taylor_order < 1)
      reject("taylor_order", std::to_string(taylor_order), "must be >= 1 when directions are given");
  }
}

StreamLayout::StreamLayout(StreamSpec spec) : spec_(std::move(spec)) {
  if (spec_.tangents.size() == 0) spec_.tangents.resize(spec_.input_dim, 0);
  if (spec_.taylor_directions.size() == 0) spec_.taylor_directions.resize(spec_.input_dim, 0);
  spec_.validate();
  tangents_ = static_cast<int>(spec_.tangents.cols());
  operators_ = static_cast<int>(spec_.operators.size());
  taylor_dirs_ = static_cast<int>(spec_.taylor_directions.cols());
  taylor_order_ = taylor_dirs_ > 0 ? spec_.taylor_order : 0;
  for (const Eigen::MatrixXd& c : spec_.operators) {
    std::vector<OperatorTerm> terms;
    for (int i = 0; i < tangents_; ++i)
      for (int j = i; j < tangents_; ++j) {
        const double coefficient = i == j ? c(i, i) : c(i, j) + c(j, i);
        if (coefficient != 0) terms.push_back({i, j, coefficient});
      }
    terms_.push_back(std::move(terms));
  }
}

int StreamLayout::forward_order() const {
  if (taylor_order_ > 0) return std::max(taylor_order_, operators_ > 0 ? 2 : 1);
  if (operators_ > 0) return 2;
  return tangents_ > 0 ? 1 : 0;
}

template <typename Scalar>
void seed_input_streams(const StreamLayout& layout, const Eigen::Ref<const Matrix<Scalar>>& x,
                        Streams<Scalar>& out,
                        const Eigen::Ref<const Matrix<Scalar>>* point_tangents) {
  const Eigen::Index n = x.rows();
  const int d = layout.input_dim();
  if (x.cols() != d)
    throw std::invalid_argument("seed_input_streams: points have " + std::to_string(x.cols()) +
                                " columns, the stream spec expects " + std::to_string(d));
  out.resize(n, layout.count(), d);
  out.values() = x;
  const StreamSpec& spec = layout.spec();
  if (point_tangents && (point_tangents->rows() != n || point_tangents->cols() != d * layout.tangents()))
    throw std::invalid_argument("seed_input_streams: per-point tangents are " +
                                std::to_string(point_tangents->rows()) + " x " +
                                std::to_string(point_tangents->cols()) + ", expected " +
                                std::to_string(n) + " x " + std::to_string(d * layout.tangents()) +
                                " (points x input_dim * tangents)");
  for (int i = 0; i < layout.tangents(); ++i) {
    if (point_tangents)
      out.stream(layout.tangent(i)) = point_tangents->middleCols(i * d, d);
    else
      out.stream(layout.tangent(i)).rowwise() = spec.tangents.col(i).transpose().cast<Scalar>();
  }
  for (int q = 0; q < layout.operators(); ++q) out.stream(layout.op(q)).setZero();
  for (int p = 0; p < layout.taylor_dirs(); ++p) {
    out.stream(layout.taylor(p, 1)).rowwise() =
        spec.taylor_directions.col(p).transpose().cast<Scalar>();
    for (int k = 2; k <= layout.taylor_order(); ++k) out.stream(layout.taylor(p, k)).setZero();
  }
}

template void seed_input_streams<float>(const StreamLayout&, const Eigen::Ref<const Matrix<float>>&,
                                        Streams<float>&, const Eigen::Ref<const Matrix<float>>*);
template void seed_input_streams<double>(const StreamLayout&,
                                         const Eigen::Ref<const Matrix<double>>&, Streams<double>&,
                                         const Eigen::Ref<const Matrix<double>>*);

Eigen::MatrixXd biharmonic_directions_2d() {
  Eigen::MatrixXd w(2, 3);
  for (int p = 0; p < 3; ++p) {
    const double angle = p * std::numbers::pi / 3;
    w.col(p) << std::cos(angle), std::sin(angle);
  }
  return w;
}

}  // namespace nfield::autodiff
