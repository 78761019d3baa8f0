// SPDX-License-Identifier: MIT
#include "fields/integrated_positional.h"

#include <cmath>
#include <numbers>
#include <stdexcept>
#include <vector>

#include "fields/activations.h"
#include "fields/encoding_type.h"

namespace nfield::fields {
namespace {

constexpr int kMaxFrequencies = 24;  // as the positional encoding

// e^z, every derivative e^z.
template <typename Scalar>
class Exp final : public autodiff::ElementwiseFunction<Scalar> {
 public:
  void derivatives(const Eigen::Ref<const autodiff::Matrix<Scalar>>& z, int max_order,
                   std::vector<autodiff::Matrix<Scalar>>& tables) const override {
    tables.resize(max_order + 1);
    tables[0] = z.array().exp().matrix();
    for (int m = 1; m <= max_order; ++m) tables[m] = tables[0];
  }
};

}  // namespace

template <typename Scalar>
IntegratedPositionalEncoding<Scalar>::IntegratedPositionalEncoding(int positions, int frequencies,
                                                                   bool include_input)
    : positions_(positions),
      include_input_(include_input),
      sine_(make_activation<Scalar>({"sine", 1.0})),
      exp_(std::make_shared<Exp<Scalar>>()) {
  if (positions < 1 || frequencies < 1)
    throw std::logic_error("IntegratedPositionalEncoding: needs positions and frequencies >= 1");
  const Eigen::Index m = static_cast<Eigen::Index>(frequencies) * positions;
  Eigen::MatrixXd weights = Eigen::MatrixXd::Zero(2 * m, positions);
  Eigen::MatrixXd damping = Eigen::MatrixXd::Zero(2 * m, positions);
  Eigen::VectorXd offsets(2 * m);
  offsets << Eigen::VectorXd::Zero(m), Eigen::VectorXd::Constant(m, std::numbers::pi / 2);
  for (int l = 0; l < frequencies; ++l)
    for (int i = 0; i < positions; ++i) {
      const double omega = std::ldexp(std::numbers::pi, l);
      for (const Eigen::Index row : {Eigen::Index{l} * positions + i, m + Eigen::Index{l} * positions + i}) {
        weights(row, i) = omega;
        damping(row, i) = -0.5 * omega * omega;
      }
    }
  weights_ = weights.cast<Scalar>();
  damping_ = damping.cast<Scalar>();
  offsets_ = offsets.transpose().cast<Scalar>();
}

// saved = [z, w, s, g, the sine's tables …, the exponential's tables …] (as many of each).
template <typename Scalar>
void IntegratedPositionalEncoding<Scalar>::forward(const autodiff::StreamLayout& layout,
                                                   const Scalar*,
                                                   const autodiff::Streams<Scalar>& in,
                                                   autodiff::Streams<Scalar>& out,
                                                   autodiff::SavedTensors<Scalar>* saved) const {
  const Eigen::Index k = positions_, m = weights_.rows();
  thread_local autodiff::Streams<Scalar> z, w, s, g, y;
  thread_local std::vector<autodiff::Matrix<Scalar>> sine_tables, exp_tables;
  z.resize(in.points, in.count, m);
  z.data.noalias() = in.data.leftCols(k) * weights_.transpose();
  z.values().rowwise() += offsets_.row(0);
  w.resize(in.points, in.count, m);
  w.data.noalias() = in.data.rightCols(k) * damping_.transpose();
  const int order = layout.forward_order() + (saved ? 1 : 0);
  sine_->derivatives(z.values(), order, sine_tables);
  exp_->derivatives(w.values(), order, exp_tables);
  autodiff::elementwise_forward(layout, sine_tables, z, s);
  autodiff::elementwise_forward(layout, exp_tables, w, g);
  autodiff::product_forward(layout, s, g, y);
  const Eigen::Index d = include_input_ ? k : 0;
  out.resize(in.points, in.count, d + m);
  if (d > 0) out.data.leftCols(d) = in.data.leftCols(k);
  out.data.rightCols(m) = y.data;
  if (saved) {
    saved->clear();
    for (const auto* streams : {&z, &w, &s, &g}) saved->push_back(streams->data);
    saved->insert(saved->end(), sine_tables.begin(), sine_tables.end());
    saved->insert(saved->end(), exp_tables.begin(), exp_tables.end());
  }
}

template <typename Scalar>
void IntegratedPositionalEncoding<Scalar>::backward(const autodiff::StreamLayout& layout,
                                                    const Scalar*,
                                                    const autodiff::Streams<Scalar>& in,
                                                    const autodiff::SavedTensors<Scalar>& saved,
                                                    autodiff::Streams<Scalar>& out_adjoint, Scalar*,
                                                    autodiff::Streams<Scalar>* in_adjoint) const {
  if (!in_adjoint) return;
  const Eigen::Index k = positions_, m = weights_.rows();
  thread_local autodiff::Streams<Scalar> z, w, s, g, y_bar, s_bar, g_bar, z_bar, w_bar;
  thread_local std::vector<autodiff::Matrix<Scalar>> sine_tables, exp_tables;
  auto restore = [&](autodiff::Streams<Scalar>& streams, const autodiff::Matrix<Scalar>& data) {
    streams.points = in.points;
    streams.count = in.count;
    streams.data = data;
  };
  restore(z, saved[0]);
  restore(w, saved[1]);
  restore(s, saved[2]);
  restore(g, saved[3]);
  const size_t tables = (saved.size() - 4) / 2;
  sine_tables.assign(saved.begin() + 4, saved.begin() + 4 + tables);
  exp_tables.assign(saved.begin() + 4 + tables, saved.end());
  y_bar.resize(in.points, in.count, m);
  y_bar.data = out_adjoint.data.rightCols(m);
  autodiff::product_backward(layout, s, g, y_bar, s_bar, g_bar);
  autodiff::elementwise_backward(layout, sine_tables, z, s_bar, z_bar);
  autodiff::elementwise_backward(layout, exp_tables, w, g_bar, w_bar);
  in_adjoint->resize(in.points, in.count, 2 * k);
  in_adjoint->data.leftCols(k).noalias() = z_bar.data * weights_;
  if (include_input_) in_adjoint->data.leftCols(k) += out_adjoint.data.leftCols(k);
  in_adjoint->data.rightCols(k).noalias() = w_bar.data * damping_;
}

template class IntegratedPositionalEncoding<float>;
template class IntegratedPositionalEncoding<double>;

void IntegratedPositionalOptions::validate() const {
  if (frequencies < 1 || frequencies > kMaxFrequencies)
    throw std::invalid_argument("encoding.frequencies = " + std::to_string(frequencies) +
                                ": must be in [1, " + std::to_string(kMaxFrequencies) + "]");
}

namespace {

class IntegratedPositionalType final
    : public EncodingTypeOf<IntegratedPositionalType, IntegratedPositionalOptions> {
 public:
  bool reads_variances() const override { return true; }
  void validate(const EncodingOptions& o) const override { own(o).validate(); }
  void validate_inputs(const EncodingOptions&, int input_dim) const override {
    if (input_dim < 2 || input_dim % 2 != 0)
      throw std::invalid_argument(
          "encoding.type = integrated_positional: reads a mean and a variance per coordinate, "
          "[μ₁ … μ_k, σ₁² … σ_k²], so its inputs must be an even number, not " +
          std::to_string(input_dim));
  }
  template <typename Scalar>
  static std::unique_ptr<autodiff::Module<Scalar>> make(const EncodingOptions& o, int input_dim) {
    return std::make_unique<IntegratedPositionalEncoding<Scalar>>(input_dim / 2, own(o).frequencies,
                                                                  own(o).include_input);
  }
  void read(const io::ConfigNode& e, const EncodingContext&, EncodingOptions& o) const override {
    IntegratedPositionalOptions p;
    if (e.has("frequencies")) p.frequencies = e.get_in_range("frequencies", 1, kMaxFrequencies);
    p.include_input = e.get_or("include_input", true);
    o.own = p;
  }
  void write(const EncodingOptions& o, const EncodingContext&, YAML::Node& n) const override {
    n["frequencies"] = own(o).frequencies;
    n["include_input"] = own(o).include_input;
  }
  void save(io::H5Writer& file, const std::string& group, const EncodingOptions& o) const override {
    file.write_attribute(group, "encoding_frequencies", own(o).frequencies);
    file.write_attribute(group, "encoding_include_input", static_cast<std::int64_t>(own(o).include_input));
  }
  void load(const io::H5Reader& file, const std::string& group, EncodingOptions& o) const override {
    IntegratedPositionalOptions p;
    if (file.has_attribute(group, "encoding_frequencies"))
      p.frequencies = static_cast<int>(file.read_attribute<std::int64_t>(group, "encoding_frequencies"));
    if (file.has_attribute(group, "encoding_include_input"))
      p.include_input = file.read_attribute<std::int64_t>(group, "encoding_include_input") != 0;
    o.own = p;
  }
};

}  // namespace

std::unique_ptr<const EncodingType> make_integrated_positional_type() {
  return std::make_unique<IntegratedPositionalType>();
}

}  // namespace nfield::fields
