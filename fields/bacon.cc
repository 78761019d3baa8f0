// SPDX-License-Identifier: MIT
//
// BACON's lattice and its network module (fields/bacon.h); the field type's keys are in
// bacon_type.cc.
#include "fields/bacon.h"

#include <algorithm>
#include <any>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

#include "autodiff/elementwise.h"

namespace nfield::fields {

using autodiff::Matrix;
using autodiff::Streams;
using autodiff::Vector;

namespace {

[[noreturn]] void reject(const std::string& key, const std::string& value, const std::string& rule) {
  throw std::invalid_argument("field." + key + " = " + value + ": " + rule);
}

double uniform(std::mt19937_64& rng, double a) {
  return a * (2.0 * static_cast<double>(rng() >> 11) * 0x1.0p-53 - 1.0);
}

// An integer uniform in [−m, m] (m ≥ 0), by rejection, independent of library distributions.
int lattice_index(std::mt19937_64& rng, int m) {
  const std::uint64_t range = 2 * static_cast<std::uint64_t>(m) + 1;
  const std::uint64_t limit = ~std::uint64_t{0} - ~std::uint64_t{0} % range;
  std::uint64_t r;
  do r = rng();
  while (r >= limit);
  return static_cast<int>(r % range) - m;
}

// σ⁽ᵐ⁾ of sin at u: sin(u + mπ/2), m = 0 … order.
template <typename Scalar>
void sine_tables(const Eigen::Ref<const Matrix<Scalar>>& u, int order, std::vector<Matrix<Scalar>>& tables) {
  tables.resize(static_cast<size_t>(order) + 1);
  tables[0] = u.array().sin().matrix();
  if (order >= 1) tables[1] = u.array().cos().matrix();
  for (int m = 2; m <= order; ++m) tables[m] = -tables[m - 2];
}

template <typename Scalar>
Streams<Scalar> as_streams(const Matrix<Scalar>& data, Eigen::Index points, int count) {
  Streams<Scalar> s;
  s.points = points;
  s.count = count;
  s.data = data;
  return s;
}

std::string list(const std::vector<int>& v) {
  std::string s = "[";
  for (size_t i = 0; i < v.size(); ++i) s += (i ? ", " : "") + std::to_string(v[i]);
  return s + "]";
}

}  // namespace

const BaconOptions& bacon_options(const FieldOptions& options) {
  static const BaconOptions defaults = [] {
    BaconOptions o;
    o.resolution = {64, 128, 256};
    return o;
  }();
  const auto* own = std::any_cast<BaconOptions>(&options.extension);
  return own ? *own : defaults;
}

std::vector<int> BaconOptions::head_layers(int layers) const {
  if (!output_layers.empty()) return output_layers;
  std::vector<int> heads;
  for (int s = 0; s < scales(); ++s) heads.push_back(layers - scales() + s);
  return heads;
}

void BaconOptions::validate(int layers) const {
  if (!resolution.empty() && !max_frequency.empty())
    reject("max_frequency", "[…]", "give either max_frequency or resolution, not both");
  if (scales() < 1) reject("resolution", "[]", "needs at least one scale (resolution or max_frequency)");
  for (int s = 0; s < scales(); ++s) {
    if (!resolution.empty()) {
      if (resolution[s] < 2 || resolution[s] > (1 << 20))
        reject("resolution[" + std::to_string(s) + "]", std::to_string(resolution[s]), "must be in [2, 1048576]");
      if (s > 0 && resolution[s] <= resolution[s - 1])
        reject("resolution", list(resolution), "must increase from scale to scale");
    } else {
      if (!(max_frequency[s] > 0) || max_frequency[s] > 1e6)
        reject("max_frequency[" + std::to_string(s) + "]", std::to_string(max_frequency[s]), "must be in (0, 1e6]");
      if (s > 0 && !(max_frequency[s] > max_frequency[s - 1]))
        reject("max_frequency", std::to_string(max_frequency[s]), "must increase from scale to scale");
    }
  }
  if (!output_layers.empty() && static_cast<int>(output_layers.size()) != scales())
    reject("output_layers", list(output_layers),
           "needs one layer per scale (" + std::to_string(scales()) + ")");
  const std::vector<int> heads = head_layers(layers);
  for (size_t s = 0; s < heads.size(); ++s) {
    if (heads[s] < 0 || heads[s] >= layers)
      reject("output_layers", list(heads), "layers are 0 … " + std::to_string(layers - 1) +
                                                " (one per entry of hidden); need at least one layer per scale");
    if (s > 0 && heads[s] <= heads[s - 1]) reject("output_layers", list(heads), "must increase");
  }
  if (heads.back() != layers - 1)
    reject("output_layers", list(heads), "the last scale must read the last layer (" +
                                             std::to_string(layers - 1) + "): later layers would be unused");
  if (period < 1 || period > 64) reject("period", std::to_string(period), "must be in [1, 64] (box widths)");
  if (output_scale < -1 || output_scale >= scales())
    reject("output_scale", std::to_string(output_scale),
           "must be a scale in 0 … " + std::to_string(scales() - 1) + " (or -1: the finest)");
}

Eigen::VectorXd bacon_periods(const FieldOptions& o) {
  Eigen::VectorXd period(o.input_dim);
  for (int k = 0; k < o.input_dim; ++k) {
    const bool set = static_cast<int>(o.encoding.lower.size()) == o.input_dim &&
                     static_cast<int>(o.encoding.upper.size()) == o.input_dim;
    period(k) = (set ? o.encoding.upper[k] - o.encoding.lower[k] : 2.0) * bacon_options(o).period;
  }
  return period;
}

Eigen::MatrixXi bacon_cutoff_steps(const FieldOptions& o) {
  const BaconOptions& b = bacon_options(o);
  const Eigen::VectorXd period = bacon_periods(o);
  Eigen::MatrixXi steps(b.scales(), o.input_dim);
  for (int s = 0; s < b.scales(); ++s)
    for (int k = 0; k < o.input_dim; ++k)
      steps(s, k) = b.resolution.empty()
                        ? static_cast<int>(std::floor(b.max_frequency[s] * period(k) * (1 + 1e-12)))
                        : b.period * b.resolution[s] / 2;
  return steps;
}

Eigen::MatrixXi bacon_layer_bounds(const FieldOptions& o) {
  const BaconOptions& b = bacon_options(o);
  const int layers = static_cast<int>(o.hidden.size());
  const std::vector<int> heads = b.head_layers(layers);
  const Eigen::MatrixXi steps = bacon_cutoff_steps(o);
  Eigen::MatrixXi bounds = Eigen::MatrixXi::Zero(layers, o.input_dim);
  int first = 0;
  for (size_t s = 0; s < heads.size(); ++s) {
    const int count = heads[s] - first + 1;
    for (int k = 0; k < o.input_dim; ++k) {
      const int budget = steps(static_cast<Eigen::Index>(s), k) - (s > 0 ? steps(static_cast<Eigen::Index>(s) - 1, k) : 0);
      // Spread evenly; the first budget % count layers take one more.
      for (int j = 0; j < count; ++j) bounds(first + j, k) = budget / count + (j < budget % count ? 1 : 0);
    }
    first = heads[s] + 1;
  }
  return bounds;
}

std::vector<Eigen::MatrixXd> bacon_filter_frequencies(const FieldOptions& o) {
  const Eigen::MatrixXi bounds = bacon_layer_bounds(o);
  const Eigen::VectorXd period = bacon_periods(o);
  std::mt19937_64 rng(o.seed ^ 0xBAC0'4F11'7E25'0000ULL);
  std::vector<Eigen::MatrixXd> omega;
  for (size_t i = 0; i < o.hidden.size(); ++i) {
    Eigen::MatrixXd w(o.hidden[i], o.input_dim);
    for (Eigen::Index r = 0; r < w.rows(); ++r)
      for (int k = 0; k < o.input_dim; ++k)
        w(r, k) = 2.0 * std::numbers::pi / period(k) * lattice_index(rng, bounds(static_cast<Eigen::Index>(i), k));
    omega.push_back(std::move(w));
  }
  return omega;
}

// ---------------------------------------------------------------------------------------

template <typename Scalar>
struct BaconNetwork<Scalar>::Sink {
  Scalar* gradient = nullptr;                       // summed over points, or
  autodiff::JacobianRows<Scalar>* jacobian = nullptr;  // point n's term in row n

  // z = W a + b over all streams: W̄ (out × in) and b̄ from z̄ and a.
  void affine(Eigen::Index offset, const Streams<Scalar>& z_bar, const Streams<Scalar>& a) const {
    const Eigen::Index out = z_bar.width(), in = a.width(), n = a.points;
    if (gradient) {
      Eigen::Map<Matrix<Scalar>>(gradient + offset, out, in).noalias() += z_bar.data.transpose() * a.data;
      Eigen::Map<Vector<Scalar>>(gradient + offset + out * in, out) += z_bar.values().colwise().sum().transpose();
      return;
    }
    const Matrix<Scalar> zt = z_bar.data.transpose(), at = a.data.transpose();
    for (Eigen::Index p = 0; p < n; ++p) {
      Eigen::Map<Matrix<Scalar>> w(&(*jacobian)(p, offset), out, in);
      w.noalias() = zt.col(p) * at.col(p).transpose();
      for (int s = 1; s < a.count; ++s) w.noalias() += zt.col(s * n + p) * at.col(s * n + p).transpose();
      Eigen::Map<Vector<Scalar>>(&(*jacobian)(p, offset + out * in), out) = zt.col(p);
    }
  }
  // u = x Ωᵀ + φ: φ̄ = ū⁰ (the phase enters the value rows only).
  void phase(Eigen::Index offset, const Streams<Scalar>& u_bar) const {
    const Eigen::Index width = u_bar.width();
    if (gradient) {
      Eigen::Map<Vector<Scalar>>(gradient + offset, width) += u_bar.values().colwise().sum().transpose();
      return;
    }
    for (Eigen::Index p = 0; p < u_bar.points; ++p)
      Eigen::Map<Vector<Scalar>>(&(*jacobian)(p, offset), width) = u_bar.values().row(p).transpose();
  }
};

template <typename Scalar>
BaconNetwork<Scalar>::BaconNetwork(const FieldOptions& o)
    : dim_(o.input_dim), outputs_(o.output_dim), omega_(bacon_filter_frequencies(o)) {
  Eigen::Index offset = 0;
  for (size_t i = 0; i < o.hidden.size(); ++i) {
    Layer layer;
    layer.width = o.hidden[i];
    if (i > 0) {
      layer.weight = offset;
      offset += layer.width * layers_.back().width + layer.width;
    }
    layer.phase = offset;
    offset += layer.width;
    layers_.push_back(layer);
    omega_scalar_.push_back(omega_[i].cast<Scalar>());
  }
  for (int l : bacon_options(o).head_layers(static_cast<int>(o.hidden.size()))) {
    heads_.push_back({l, offset});
    offset += outputs_ * layers_[static_cast<size_t>(l)].width + outputs_;
  }
  parameter_count_ = offset;
}

template <typename Scalar>
bool BaconNetwork<Scalar>::initialize(Scalar* params, std::mt19937_64& rng) const {
  auto affine = [&](Eigen::Index offset, Eigen::Index out, Eigen::Index in) {
    const double w = std::sqrt(6.0 / static_cast<double>(in)), b = 1.0 / std::sqrt(static_cast<double>(in));
    for (Eigen::Index i = 0; i < out * in; ++i) params[offset + i] = static_cast<Scalar>(uniform(rng, w));
    for (Eigen::Index i = 0; i < out; ++i) params[offset + out * in + i] = static_cast<Scalar>(uniform(rng, b));
  };
  for (size_t i = 0; i < layers_.size(); ++i) {
    const Layer& layer = layers_[i];
    if (i > 0) affine(layer.weight, layer.width, layers_[i - 1].width);
    for (Eigen::Index r = 0; r < layer.width; ++r)
      params[layer.phase + r] = static_cast<Scalar>(uniform(rng, std::numbers::pi));
  }
  for (const Head& head : heads_) affine(head.offset, outputs_, layers_[static_cast<size_t>(head.layer)].width);
  return true;
}

// Tape per layer i, from i·stride: u, g, v (empty for layer 0), z, then the sine's tables.
template <typename Scalar>
void BaconNetwork<Scalar>::run_forward(const autodiff::StreamLayout& layout, const Scalar* params,
                                       const Streams<Scalar>& in, Streams<Scalar>& out,
                                       autodiff::SavedTensors<Scalar>& tape, int table_order) const {
  const Eigen::Index n = in.points;
  const int stride = tape_stride(layout);
  tape.resize(layers_.size() * static_cast<size_t>(stride));
  Streams<Scalar> u, g, v, z, previous;
  std::vector<Matrix<Scalar>> tables;
  out.resize(n, in.count, output_width());
  for (size_t i = 0; i < layers_.size(); ++i) {
    const Layer& layer = layers_[i];
    u.resize(n, in.count, layer.width);
    u.data.noalias() = in.data * omega_scalar_[i].transpose();
    u.values().rowwise() += Eigen::Map<const Vector<Scalar>>(params + layer.phase, layer.width).transpose();
    sine_tables<Scalar>(u.values(), table_order, tables);
    autodiff::elementwise_forward(layout, tables, u, g);
    if (i == 0) {
      z = g;
    } else {
      const Eigen::Index in_width = layers_[i - 1].width;
      const Eigen::Map<const Matrix<Scalar>> weight(params + layer.weight, layer.width, in_width);
      v.resize(n, in.count, layer.width);
      v.data.noalias() = previous.data * weight.transpose();
      v.values().rowwise() +=
          Eigen::Map<const Vector<Scalar>>(params + layer.weight + layer.width * in_width, layer.width).transpose();
      autodiff::product_forward(layout, g, v, z);
    }
    for (size_t s = 0; s < heads_.size(); ++s) {
      if (heads_[s].layer != static_cast<int>(i)) continue;
      const Eigen::Map<const Matrix<Scalar>> h(params + heads_[s].offset, outputs_, layer.width);
      auto y = out.data.middleCols(static_cast<Eigen::Index>(s) * outputs_, outputs_);
      y.noalias() = z.data * h.transpose();
      out.values().middleCols(static_cast<Eigen::Index>(s) * outputs_, outputs_).rowwise() +=
          Eigen::Map<const Vector<Scalar>>(params + heads_[s].offset + outputs_ * layer.width, outputs_).transpose();
    }
    Matrix<Scalar>* t = &tape[i * static_cast<size_t>(stride)];
    t[0] = std::move(u.data);
    t[1] = std::move(g.data);
    if (i > 0) t[2] = std::move(v.data);
    t[3] = z.data;
    for (size_t m = 0; m < tables.size(); ++m) t[4 + m] = std::move(tables[m]);
    std::swap(previous, z);
  }
}

template <typename Scalar>
void BaconNetwork<Scalar>::forward(const autodiff::StreamLayout& layout, const Scalar* params,
                                   const Streams<Scalar>& in, Streams<Scalar>& out,
                                   autodiff::SavedTensors<Scalar>* saved) const {
  if (saved) {
    run_forward(layout, params, in, out, *saved, layout.forward_order() + 1);
    return;
  }
  thread_local autodiff::SavedTensors<Scalar> tape;
  run_forward(layout, params, in, out, tape, layout.forward_order());
}

template <typename Scalar>
void BaconNetwork<Scalar>::run_backward(const autodiff::StreamLayout& layout, const Scalar* params,
                                        const Streams<Scalar>& in, const autodiff::SavedTensors<Scalar>& saved,
                                        const Streams<Scalar>& out_adjoint, Sink& sink,
                                        Streams<Scalar>* in_adjoint) const {
  const Eigen::Index n = in.points;
  const int count = in.count, stride = tape_stride(layout);
  auto tape = [&](size_t i, int k) -> const Matrix<Scalar>& { return saved[i * static_cast<size_t>(stride) + k]; };
  std::vector<Streams<Scalar>> z_bar(layers_.size());
  for (size_t i = 0; i < layers_.size(); ++i) {
    z_bar[i].resize(n, count, layers_[i].width);
    z_bar[i].data.setZero();
  }
  for (size_t s = 0; s < heads_.size(); ++s) {
    const size_t l = static_cast<size_t>(heads_[s].layer);
    const Eigen::Index width = layers_[l].width;
    Streams<Scalar> y_bar;
    y_bar.resize(n, count, outputs_);
    y_bar.data = out_adjoint.data.middleCols(static_cast<Eigen::Index>(s) * outputs_, outputs_);
    sink.affine(heads_[s].offset, y_bar, as_streams(tape(l, 3), n, count));
    z_bar[l].data.noalias() += y_bar.data * Eigen::Map<const Matrix<Scalar>>(params + heads_[s].offset, outputs_, width);
  }
  if (in_adjoint) {
    in_adjoint->resize(n, count, dim_);
    in_adjoint->data.setZero();
  }
  std::vector<Matrix<Scalar>> tables(static_cast<size_t>(layout.forward_order()) + 2);
  Streams<Scalar> g_bar, v_bar, u_bar;
  for (size_t i = layers_.size(); i-- > 0;) {
    const Layer& layer = layers_[i];
    const Streams<Scalar> g = as_streams(tape(i, 1), n, count);
    if (i == 0) {
      g_bar = std::move(z_bar[0]);
    } else {
      const Streams<Scalar> v = as_streams(tape(i, 2), n, count);
      autodiff::product_backward(layout, g, v, z_bar[i], g_bar, v_bar);
      const Eigen::Index in_width = layers_[i - 1].width;
      sink.affine(layer.weight, v_bar, as_streams(tape(i - 1, 3), n, count));
      z_bar[i - 1].data.noalias() +=
          v_bar.data * Eigen::Map<const Matrix<Scalar>>(params + layer.weight, layer.width, in_width);
    }
    for (size_t m = 0; m < tables.size(); ++m) tables[m] = tape(i, 4 + static_cast<int>(m));
    autodiff::elementwise_backward(layout, tables, as_streams(tape(i, 0), n, count), g_bar, u_bar);
    sink.phase(layer.phase, u_bar);
    if (in_adjoint) in_adjoint->data.noalias() += u_bar.data * omega_scalar_[i];
  }
}

template <typename Scalar>
void BaconNetwork<Scalar>::backward(const autodiff::StreamLayout& layout, const Scalar* params,
                                    const Streams<Scalar>& in, const autodiff::SavedTensors<Scalar>& saved,
                                    Streams<Scalar>& out_adjoint, Scalar* gradient,
                                    Streams<Scalar>* in_adjoint) const {
  thread_local std::vector<Scalar> discard;
  if (!gradient) {
    discard.assign(static_cast<size_t>(parameter_count_), Scalar(0));
    gradient = discard.data();
  }
  Sink sink{gradient, nullptr};
  run_backward(layout, params, in, saved, out_adjoint, sink, in_adjoint);
}

template <typename Scalar>
void BaconNetwork<Scalar>::backward_per_point(const autodiff::StreamLayout& layout, const Scalar* params,
                                              const Streams<Scalar>& in,
                                              const autodiff::SavedTensors<Scalar>& saved,
                                              Streams<Scalar>& out_adjoint,
                                              autodiff::JacobianRows<Scalar> jacobian,
                                              Streams<Scalar>* in_adjoint) const {
  Sink sink{nullptr, &jacobian};
  run_backward(layout, params, in, saved, out_adjoint, sink, in_adjoint);
}

template class BaconNetwork<float>;
template class BaconNetwork<double>;

}  // namespace nfield::fields
