// SPDX-License-Identifier: MIT
#include "fields/acorn.h"

#include <algorithm>
#include <any>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

namespace nfield::fields {

using autodiff::Matrix;
using autodiff::StreamLayout;
using autodiff::Streams;

namespace {

[[noreturn]] void reject(const std::string& key, const std::string& value, const std::string& rule) {
  throw std::invalid_argument("field." + key + " = " + value + ": " + rule);
}

void check_range(const std::string& key, int value, int lowest, int highest) {
  if (value < lowest || value > highest)
    reject(key, std::to_string(value),
           "must be in [" + std::to_string(lowest) + ", " + std::to_string(highest) + "]");
}

double uniform_draw(std::mt19937_64& rng, double bound) {
  return bound * (2.0 * static_cast<double>(rng() >> 11) * 0x1.0p-53 - 1.0);
}

}  // namespace

void AcornOptions::validate(int input_dim) const {
  if (input_dim < 1 || input_dim > 3)
    reject("input_dim", std::to_string(input_dim), "acorn takes 1, 2 or 3 inputs");
  check_range("features", features, 1, 256);
  check_range("grid", grid, 2, 256);
  double grid_size = features;
  for (int j = 0; j < input_dim; ++j) grid_size *= grid;
  if (grid_size > (1 << 20))
    reject("grid", std::to_string(grid), "features · grid^d must be at most 2^20 numbers per block");
  if (encoder_hidden.empty()) reject("encoder_hidden", "[]", "needs at least one hidden layer");
  for (size_t i = 0; i < encoder_hidden.size(); ++i)
    check_range("encoder_hidden[" + std::to_string(i) + "]", encoder_hidden[i], 1, 4096);
  check_range("encoder_octaves", encoder_octaves, 0, 16);
  check_range("max_level", max_level, 0, max_tree_level(input_dim));
  check_range("initial_level", initial_level, 0, max_level);
  const int initial_blocks = 1 << (input_dim * initial_level);
  check_range("max_blocks", max_blocks, initial_blocks, 4096);
  check_range("allocate_every", allocate_every, 0, 1 << 30);
  if (!(split_factor > 0 && split_factor < 1))
    reject("split_factor", std::to_string(split_factor), "must be in (0, 1)");
  if (!(freeze_below >= 0 && std::isfinite(freeze_below)))
    reject("freeze_below", std::to_string(freeze_below), "must be a finite number >= 0");
  if (tree && tree->dim() != input_dim)
    reject("input_dim", std::to_string(input_dim),
           "the block tree has " + std::to_string(tree->dim()) + " dimensions");
}

const AcornOptions& acorn_options(const FieldOptions& o) {
  static const AcornOptions defaults;
  const auto* own = std::any_cast<AcornOptions>(&o.extension);
  return own ? *own : defaults;
}

std::shared_ptr<BlockTree> acorn_tree(FieldOptions& o) {
  auto* own = std::any_cast<AcornOptions>(&o.extension);
  if (!own) {
    o.extension = AcornOptions{};
    own = std::any_cast<AcornOptions>(&o.extension);
  }
  if (!own->tree) own->tree = std::make_shared<BlockTree>(o.input_dim, own->max_level, own->initial_level);
  return own->tree;
}

void restore_block_tree(const FieldOptions& saved, const FieldOptions& live) {
  const auto* from = std::any_cast<AcornOptions>(&saved.extension);
  const auto* to = std::any_cast<AcornOptions>(&live.extension);
  if (!from || !to || !from->tree || !to->tree) return;
  to->tree->set_blocks(from->tree->blocks());
}

template <typename Scalar>
AcornEncoding<Scalar>::AcornEncoding(const FieldOptions& options) {
  const AcornOptions& a = acorn_options(options);
  dim_ = options.input_dim;
  features_ = a.features;
  grid_ = a.grid;
  octaves_ = a.encoder_octaves;
  max_level_ = a.max_level;
  tree_ = a.tree ? a.tree : std::make_shared<BlockTree>(dim_, a.max_level, a.initial_level);
  widths_.push_back(a.encoder_inputs(dim_));
  widths_.insert(widths_.end(), a.encoder_hidden.begin(), a.encoder_hidden.end());
  int grid_size = features_;
  for (int j = 0; j < dim_; ++j) grid_size *= grid_;
  widths_.push_back(grid_size);
  for (size_t l = 1; l < widths_.size(); ++l) parameters_ += static_cast<Eigen::Index>(widths_[l]) * (widths_[l - 1] + 1);
  for (int j = 0; j < dim_; ++j) {
    const auto sj = static_cast<size_t>(j);
    lower_[j] = options.encoding.lower.empty() ? 0.0 : options.encoding.lower[sj];
    range_[j] = options.encoding.upper.empty() ? 1.0 : options.encoding.upper[sj] - lower_[j];
  }
}

template <typename Scalar>
bool AcornEncoding<Scalar>::initialize(Scalar* params, std::mt19937_64& rng) const {
  for (size_t l = 1; l < widths_.size(); ++l) {
    const int in = widths_[l - 1], out = widths_[l];
    const bool last = l + 1 == widths_.size();
    const double bound = last ? std::sqrt(6.0 / (in + out)) : std::sqrt(6.0 / in);
    for (Eigen::Index i = 0; i < static_cast<Eigen::Index>(in) * out; ++i)
      *params++ = static_cast<Scalar>(uniform_draw(rng, bound));
    for (int i = 0; i < out; ++i) *params++ = Scalar(0);
  }
  return true;
}

template <typename Scalar>
autodiff::Vector<Scalar> AcornEncoding<Scalar>::encoder_input(int block) const {
  double q[4];
  const double h = tree_->size(block);
  for (int j = 0; j < dim_; ++j) q[j] = 2 * (tree_->lower(block, j) + h / 2) - 1;
  q[dim_] = max_level_ > 0 ? 2.0 * tree_->blocks()[static_cast<size_t>(block)].level / max_level_ - 1 : 0.0;
  const int n = dim_ + 1;
  autodiff::Vector<Scalar> z(n * (1 + 2 * octaves_));
  for (int j = 0; j < n; ++j) z(j) = static_cast<Scalar>(q[j]);
  for (int k = 0; k < octaves_; ++k)
    for (int j = 0; j < n; ++j) {
      const double w = std::ldexp(std::numbers::pi, k) * q[j];
      z(n * (1 + 2 * k) + j) = static_cast<Scalar>(std::sin(w));
      z(n * (2 + 2 * k) + j) = static_cast<Scalar>(std::cos(w));
    }
  return z;
}

template <typename Scalar>
void AcornEncoding<Scalar>::encode(const Scalar* params, const std::vector<int>& blocks,
                                   std::vector<Matrix<Scalar>>& a) const {
  const auto u = static_cast<Eigen::Index>(blocks.size());
  a.resize(widths_.size());
  a[0].resize(widths_[0], u);
  for (Eigen::Index b = 0; b < u; ++b) a[0].col(b) = encoder_input(blocks[static_cast<size_t>(b)]);
  for (size_t l = 1; l < widths_.size(); ++l) {
    const int in = widths_[l - 1], out = widths_[l];
    Eigen::Map<const Matrix<Scalar>> w(params, out, in);
    Eigen::Map<const autodiff::Vector<Scalar>> bias(params + static_cast<Eigen::Index>(out) * in, out);
    params += static_cast<Eigen::Index>(out) * (in + 1);
    a[l].noalias() = w * a[l - 1];
    a[l].colwise() += bias;
    if (l + 1 < widths_.size()) a[l] = a[l].cwiseMax(Scalar(0));
  }
}

template <typename Scalar>
autodiff::Vector<Scalar> AcornEncoding<Scalar>::block_grid(const Scalar* params, int block) const {
  std::vector<Matrix<Scalar>> a;
  encode(params, {block}, a);
  return a.back().col(0);
}

template <typename Scalar>
void AcornEncoding<Scalar>::locate(const Scalar* x, int& block, int* cell, Scalar* s) const {
  Scalar u[3];
  for (int j = 0; j < dim_; ++j) u[j] = static_cast<Scalar>((x[j] - lower_[j]) / range_[j]);
  block = tree_->locate(u);
  const double h = tree_->size(block);
  for (int j = 0; j < dim_; ++j) {
    // Past the box's faces the outer cells continue linearly.
    const Scalar p = static_cast<Scalar>((u[j] - tree_->lower(block, j)) / h * (grid_ - 1));
    int c = p >= 0 ? static_cast<int>(p) : 0;
    c = std::min(c, grid_ - 2);
    cell[j] = c;
    s[j] = p - static_cast<Scalar>(c);
  }
}

namespace {

// The 2^d corners of a cell: vertex row, weight W_v and ∂W_v/∂p_j (per grid step).
template <typename Scalar>
struct Corners {
  int count = 0;
  int row[8];
  Scalar w[8];
  Scalar dw[8][3];
};

template <typename Scalar>
void corners(int dim, int grid, const int* cell, const Scalar* s, Corners<Scalar>& k) {
  k.count = 1 << dim;
  for (int v = 0; v < k.count; ++v) {
    int row = 0, stride = 1;
    Scalar f[3], df[3];
    for (int j = 0; j < dim; ++j, stride *= grid) {
      const bool up = (v >> j) & 1;
      row += (cell[j] + (up ? 1 : 0)) * stride;
      f[j] = up ? s[j] : 1 - s[j];
      df[j] = up ? Scalar(1) : Scalar(-1);
    }
    k.row[v] = row;
    Scalar w = 1;
    for (int j = 0; j < dim; ++j) w *= f[j];
    k.w[v] = w;
    for (int j = 0; j < dim; ++j) {
      Scalar d = df[j];
      for (int m = 0; m < dim; ++m)
        if (m != j) d *= f[m];
      k.dw[v][j] = d;
    }
  }
}

void check_streams(const StreamLayout& layout) {
  if (layout.operators() > 0 || layout.taylor_dirs() > 0)
    throw std::invalid_argument(
        "acorn field: gives the value and gradient (tangent) streams only; operator and Taylor "
        "streams (second and higher derivatives) are not provided (fields/acorn.h)");
}

}  // namespace

template <typename Scalar>
void AcornEncoding<Scalar>::check_layout(const StreamLayout& layout) const {
  check_streams(layout);
}

template <typename Scalar>
void AcornEncoding<Scalar>::forward(const StreamLayout& layout, const Scalar* params,
                                    const Streams<Scalar>& in, Streams<Scalar>& out,
                                    autodiff::SavedTensors<Scalar>* saved) const {
  check_streams(layout);
  const Eigen::Index n = in.points;
  const int tangents = layout.tangents(), c_count = features_;
  thread_local std::vector<int> slots, unique;
  slots.resize(static_cast<size_t>(n));
  unique.clear();
  Scalar x[3], s[3];
  int cell[3];
  for (Eigen::Index p = 0; p < n; ++p) {
    for (int j = 0; j < dim_; ++j) x[j] = in.data(p, j);
    int block = 0;
    locate(x, block, cell, s);
    // Points come sorted by block from the allocation's sampler: search from the back.
    auto it = std::find(unique.rbegin(), unique.rend(), block);
    if (it == unique.rend()) {
      unique.push_back(block);
      slots[static_cast<size_t>(p)] = static_cast<int>(unique.size()) - 1;
    } else {
      slots[static_cast<size_t>(p)] = static_cast<int>(unique.rend() - it) - 1;
    }
  }
  std::vector<Matrix<Scalar>> layers;
  encode(params, unique, layers);
  for (size_t slot = 0; slot < unique.size(); ++slot) {
    const std::vector<double>& kept = tree_->blocks()[static_cast<size_t>(unique[slot])].grid;
    if (!kept.empty())
      layers.back().col(static_cast<Eigen::Index>(slot)) =
          Eigen::Map<const Eigen::VectorXd>(kept.data(), static_cast<Eigen::Index>(kept.size())).cast<Scalar>();
  }
  out.resize(n, in.count, c_count);
  out.data.setZero();
  Corners<Scalar> k;
  for (Eigen::Index p = 0; p < n; ++p) {
    for (int j = 0; j < dim_; ++j) x[j] = in.data(p, j);
    int block = 0;
    locate(x, block, cell, s);
    corners(dim_, grid_, cell, s, k);
    const Scalar* g = layers.back().col(slots[static_cast<size_t>(p)]).data();
    const double h = tree_->size(block);
    Scalar scale[3];
    for (int j = 0; j < dim_; ++j) scale[j] = static_cast<Scalar>((grid_ - 1) / (h * range_[j]));
    for (int v = 0; v < k.count; ++v) {
      const Scalar* row = g + static_cast<Eigen::Index>(k.row[v]) * c_count;
      for (int c = 0; c < c_count; ++c) out.data(p, c) += k.w[v] * row[c];
      for (int i = 0; i < tangents; ++i) {
        const Eigen::Index r = layout.tangent(i) * n + p;
        Scalar kappa = 0;
        for (int j = 0; j < dim_; ++j) kappa += k.dw[v][j] * scale[j] * in.data(r, j);
        for (int c = 0; c < c_count; ++c) out.data(r, c) += kappa * row[c];
      }
    }
  }
  if (saved) {
    // [0] each point's slot, [1] the blocks, then the encoder's activations.
    autodiff::SavedTensors<Scalar>& a = *saved;
    a.resize(2);
    a[0].resize(n, 1);
    for (Eigen::Index p = 0; p < n; ++p) a[0](p, 0) = static_cast<Scalar>(slots[static_cast<size_t>(p)]);
    a[1].resize(static_cast<Eigen::Index>(unique.size()), 1);
    for (size_t b = 0; b < unique.size(); ++b) a[1](static_cast<Eigen::Index>(b), 0) = static_cast<Scalar>(unique[b]);
    for (auto& m : layers) a.push_back(std::move(m));
  }
}

template <typename Scalar>
void AcornEncoding<Scalar>::backward(const StreamLayout& layout, const Scalar* params,
                                     const Streams<Scalar>& in, const autodiff::SavedTensors<Scalar>& saved,
                                     Streams<Scalar>& out_adjoint, Scalar* gradient,
                                     Streams<Scalar>* in_adjoint) const {
  if (in_adjoint)
    throw std::logic_error("acorn encoding: no input adjoint (it is a field's first module)");
  check_streams(layout);
  const Eigen::Index n = in.points;
  const int tangents = layout.tangents(), c_count = features_;
  const auto layer_count = widths_.size() - 1;
  const Matrix<Scalar>& grids = saved[2 + layer_count];
  Matrix<Scalar> delta = Matrix<Scalar>::Zero(grids.rows(), grids.cols());
  Scalar x[3], s[3];
  int cell[3];
  Corners<Scalar> k;
  for (Eigen::Index p = 0; p < n; ++p) {
    for (int j = 0; j < dim_; ++j) x[j] = in.data(p, j);
    int block = 0;
    locate(x, block, cell, s);
    corners(dim_, grid_, cell, s, k);
    Scalar* g = delta.col(static_cast<Eigen::Index>(saved[0](p, 0))).data();
    const double h = tree_->size(block);
    Scalar scale[3];
    for (int j = 0; j < dim_; ++j) scale[j] = static_cast<Scalar>((grid_ - 1) / (h * range_[j]));
    for (int v = 0; v < k.count; ++v) {
      Scalar* row = g + static_cast<Eigen::Index>(k.row[v]) * c_count;
      for (int c = 0; c < c_count; ++c) row[c] += k.w[v] * out_adjoint.data(p, c);
      for (int i = 0; i < tangents; ++i) {
        const Eigen::Index r = layout.tangent(i) * n + p;
        Scalar kappa = 0;
        for (int j = 0; j < dim_; ++j) kappa += k.dw[v][j] * scale[j] * in.data(r, j);
        for (int c = 0; c < c_count; ++c) row[c] += kappa * out_adjoint.data(r, c);
      }
    }
  }
  // Frozen blocks' kept grids are constants of the pass.
  for (Eigen::Index slot = 0; slot < delta.cols(); ++slot)
    if (!tree_->blocks()[static_cast<size_t>(saved[1](slot, 0))].grid.empty()) delta.col(slot).setZero();
  // The encoder's reverse pass, all blocks at once.
  std::vector<Eigen::Index> offset(widths_.size(), 0);
  for (size_t l = 1; l < widths_.size(); ++l)
    offset[l] = offset[l - 1] + static_cast<Eigen::Index>(widths_[l]) * (widths_[l - 1] + 1);
  for (size_t l = layer_count; l >= 1; --l) {
    const int in_w = widths_[l - 1], out_w = widths_[l];
    const Eigen::Index first = offset[l - 1];
    const Matrix<Scalar>& before = saved[2 + l - 1];
    Eigen::Map<Matrix<Scalar>> gw(gradient + first, out_w, in_w);
    Eigen::Map<autodiff::Vector<Scalar>> gb(gradient + first + static_cast<Eigen::Index>(out_w) * in_w, out_w);
    gw.noalias() += delta * before.transpose();
    gb += delta.rowwise().sum();
    if (l == 1) break;
    Eigen::Map<const Matrix<Scalar>> w(params + first, out_w, in_w);
    Matrix<Scalar> next = w.transpose() * delta;
    delta = next.cwiseProduct((before.array() > Scalar(0)).template cast<Scalar>().matrix());
  }
}

template class AcornEncoding<float>;
template class AcornEncoding<double>;

}  // namespace nfield::fields
