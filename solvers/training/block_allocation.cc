// SPDX-License-Identifier: MIT
#include "solvers/training/block_allocation.h"

#include <algorithm>
#include <numeric>
#include <sstream>
#include <stdexcept>
#include <vector>

#include "fields/acorn_allocation.h"
#include "io/text.h"

namespace nfield::solvers {

template <typename Scalar>
BlockAllocation<Scalar>::BlockAllocation(const fields::FieldOptions& field, std::uint64_t seed,
                                         std::size_t terms)
    : options_(fields::acorn_options(field)), tree_(options_.tree), dim_(field.input_dim), terms_(terms),
      rng_(seed * 0x9E3779B97F4A7C15ull + 0xAC0) {
  if (!tree_) throw std::logic_error("block allocation: the acorn field has no block tree");
  for (int j = 0; j < dim_; ++j) {
    const auto sj = static_cast<size_t>(j);
    lower_[j] = field.encoding.lower.empty() ? 0.0 : field.encoding.lower[sj];
    range_[j] = field.encoding.upper.empty() ? 1.0 : field.encoding.upper[sj] - lower_[j];
  }
}

template <typename Scalar>
void BlockAllocation<Scalar>::to_unit(const double* x, double* u) const {
  for (int j = 0; j < dim_; ++j) u[j] = (x[j] - lower_[j]) / range_[j];
}

namespace {

// Block b's feature grid at the field's parameters, from its acorn encoding (the tree's
// current layout).
template <typename Scalar>
std::vector<double> kept_grid(const fields::Field<Scalar>& field, int b) {
  const auto& modules = field.network().modules();
  for (size_t m = 0; m < modules.size(); ++m)
    if (const auto* acorn = dynamic_cast<const fields::AcornEncoding<Scalar>*>(modules[m].get())) {
      const autodiff::Vector<Scalar> g =
          acorn->block_grid(field.parameters().data() + field.network().parameter_offset(m), b);
      std::vector<double> out(static_cast<size_t>(g.size()));
      for (Eigen::Index i = 0; i < g.size(); ++i) out[static_cast<size_t>(i)] = static_cast<double>(g(i));
      return out;
    }
  throw std::logic_error("block allocation: the field has no acorn encoding");
}

}  // namespace

template <typename Scalar>
bool BlockAllocation<Scalar>::reallocate(const Eigen::MatrixXd& x, const Eigen::VectorXd& squared,
                                         const fields::Field<Scalar>* field) {
  std::vector<fields::Block> blocks = tree_->blocks();
  std::vector<double> sum(blocks.size(), 0.0);
  std::vector<long> count(blocks.size(), 0);
  double point[3], u[3];
  for (Eigen::Index p = 0; p < x.rows(); ++p) {
    for (int j = 0; j < dim_; ++j) point[j] = x(p, j);
    to_unit(point, u);
    const auto b = static_cast<size_t>(tree_->locate(u));
    sum[b] += squared(p);
    ++count[b];
  }
  bool changed = false;
  for (size_t b = 0; b < blocks.size(); ++b) {
    if (blocks[b].frozen || count[b] == 0) continue;
    const double mean = sum[b] / static_cast<double>(count[b]);
    blocks[b].error = mean * tree_->volume(static_cast<int>(b));
    if (options_.freeze_below > 0 && mean < options_.freeze_below) {
      blocks[b].frozen = true;
      if (field) blocks[b].grid = kept_grid(*field, static_cast<int>(b));
      changed = true;
    }
  }
  const fields::Allocation a = fields::allocate_blocks(blocks, dim_, tree_->max_level(), options_.max_blocks,
                                                       options_.split_factor);
  long splits = 0, merged = 0;
  for (fields::BlockChoice c : a.choices) {
    splits += c == fields::BlockChoice::kSplit;
    merged += c == fields::BlockChoice::kMerge;
  }
  splits_ += splits;
  merges_ += merged >> dim_;  // 2^d merging blocks per merge
  if (splits + merged > 0) {
    tree_->set_blocks(fields::apply_allocation(blocks, dim_, a.choices));
    return true;
  }
  tree_->mutable_blocks() = blocks;  // same layout: the new errors and flags
  return changed;
}

template <typename Scalar>
bool BlockAllocation<Scalar>::before_step(StrategyView<Scalar>& view) {
  const long step = view.step();
  if (options_.allocate_every <= 0 || step == 0 || step % options_.allocate_every != 0 || step == last_step_)
    return false;
  last_step_ = step;
  // The points of every term over the field's box, with their ‖r‖².
  std::vector<Eigen::MatrixXd> xs;
  std::vector<Eigen::VectorXd> rs;
  Eigen::Index rows = 0;
  for (std::size_t k = 0; k < terms_; ++k) {
    const TermPoints* points = &view.points(k);
    if (points->x.cols() != dim_ || !points->groups.empty() || points->x.rows() == 0) continue;
    xs.push_back(points->x);
    rs.push_back(view.squared_residuals(k));
    rows += points->x.rows();
  }
  Eigen::MatrixXd x(rows, dim_);
  Eigen::VectorXd r(rows);
  Eigen::Index at = 0;
  for (size_t t = 0; t < xs.size(); ++t) {
    x.middleRows(at, xs[t].rows()) = xs[t];
    r.segment(at, xs[t].rows()) = rs[t];
    at += xs[t].rows();
  }
  return reallocate(x, r, view.field());
}

template <typename Scalar>
void BlockAllocation<Scalar>::points_drawn(std::size_t, TermPoints& points) {
  if (points.x.cols() != dim_ || !points.groups.empty() || points.tangents.size() > 0) return;
  const Eigen::Index n = points.x.rows();
  const auto& blocks = tree_->blocks();
  std::vector<int> active;
  double volume = 0;
  for (size_t b = 0; b < blocks.size(); ++b)
    if (!blocks[b].frozen) {
      active.push_back(static_cast<int>(b));
      volume += tree_->volume(static_cast<int>(b));
    }
  if (active.empty() || n == 0) return;
  // Shares n V_b / ΣV, rounded by largest remainders.
  std::vector<Eigen::Index> share(active.size());
  std::vector<std::pair<double, size_t>> remainder(active.size());
  Eigen::Index given = 0;
  for (size_t i = 0; i < active.size(); ++i) {
    const double exact = static_cast<double>(n) * tree_->volume(active[i]) / volume;
    share[i] = static_cast<Eigen::Index>(exact);
    given += share[i];
    remainder[i] = {-(exact - static_cast<double>(share[i])), i};
  }
  std::stable_sort(remainder.begin(), remainder.end());
  for (Eigen::Index i = 0; i < n - given; ++i) ++share[remainder[static_cast<size_t>(i)].second];
  Eigen::MatrixXd x(n, dim_);
  Eigen::Index p = 0;
  for (size_t i = 0; i < active.size(); ++i) {
    const int b = active[i];
    const double h = tree_->size(b);
    for (Eigen::Index m = 0; m < share[i]; ++m, ++p)
      for (int j = 0; j < dim_; ++j) {
        const double t = static_cast<double>(rng_() >> 11) * 0x1.0p-53;
        x(p, j) = lower_[j] + range_[j] * (tree_->lower(b, j) + h * t);
      }
  }
  points.x = std::move(x);
}

template <typename Scalar>
void BlockAllocation<Scalar>::metrics(std::vector<std::pair<std::string, double>>& out) const {
  out.emplace_back("acorn_blocks", tree_->blocks().size());
  out.emplace_back("acorn_frozen", tree_->frozen());
  out.emplace_back("acorn_splits", static_cast<double>(splits_));
  out.emplace_back("acorn_merges", static_cast<double>(merges_));
}

template <typename Scalar>
void BlockAllocation<Scalar>::progress(std::vector<std::pair<std::string, double>>& out) const {
  out.emplace_back("blocks", tree_->active());
  out.emplace_back("frozen", tree_->frozen());
}

template <typename Scalar>
void BlockAllocation<Scalar>::save(io::H5Writer& file, const std::string& group) const {
  std::ostringstream engine;
  engine << rng_;
  file.write_attribute(group, "acorn_engine", engine.str());
  file.write_attribute(group, "acorn_last_step", static_cast<std::int64_t>(last_step_));
  file.write_attribute(group, "acorn_splits", static_cast<std::int64_t>(splits_));
  file.write_attribute(group, "acorn_merges", static_cast<std::int64_t>(merges_));
}

template <typename Scalar>
void BlockAllocation<Scalar>::load(const io::H5Reader& file, const std::string& group) {
  if (!file.has_attribute(group, "acorn_engine")) return;
  std::istringstream engine(file.read_attribute<std::string>(group, "acorn_engine"));
  engine >> rng_;
  last_step_ = static_cast<long>(file.read_attribute<std::int64_t>(group, "acorn_last_step"));
  splits_ = static_cast<long>(file.read_attribute<std::int64_t>(group, "acorn_splits"));
  merges_ = static_cast<long>(file.read_attribute<std::int64_t>(group, "acorn_merges"));
}

template <typename Scalar>
std::unique_ptr<TrainingStrategy<Scalar>> make_block_allocation(const fields::Field<Scalar>& field,
                                                                std::uint64_t seed, std::size_t terms) {
  if (io::to_lower(field.options().type) != "acorn") return nullptr;
  return std::make_unique<BlockAllocation<Scalar>>(field.options(), seed, terms);
}

template class BlockAllocation<float>;
template class BlockAllocation<double>;
template std::unique_ptr<TrainingStrategy<float>> make_block_allocation(const fields::Field<float>&, std::uint64_t, std::size_t);
template std::unique_ptr<TrainingStrategy<double>> make_block_allocation(const fields::Field<double>&, std::uint64_t, std::size_t);

}  // namespace nfield::solvers
