// SPDX-License-Identifier: MIT
//
// training.adaptive: residual-based adaptive refinement (RAR; Lu, Meng, Mao, Karniadakis
// 2021, DeepXDE; its options in adaptive_options.h, its registry entry,
// make_adaptive_settings, in adaptive_refinement.cc). Every `every` steps, `candidates` points
// are drawn for the residual term, ‖r‖ is evaluated there (a forward pass, no gradient), and
// the `add` points with the largest ‖r‖ join a persistent extra set (at most `max_points`,
// the oldest leaving first). Each freshly drawn batch of the term is followed by the whole
// set, so the loss keeps sampling where the equation is worst.
//
// A refinement on an Adam step draws the step's points anew. An L-BFGS or LM stage keeps the
// points it drew at its start and runs in segments of at most `every` iterations; after
// each, the set is refined and joined anew behind the stage's own points (or the points are
// redrawn, with the stage's resample_every).
//
// Pitfalls. The candidates are drawn from the trainer's engine and the term's quasi-random
// sequence, so a refinement shifts every later draw: that is part of the run, and it is
// repeated on resume because the set is in the checkpoint (trainer/adaptive_points).
// Refinement adds single points: a term over groups of points or with per-point tangents
// (rays) is refused at the first join.
#pragma once

#include "solvers/training/adaptive_options.h"
#include "solvers/training/loss_balancing.h"
#include "solvers/training/training_strategy.h"

namespace nfield::solvers {

template <typename Scalar>
class AdaptiveRefinement final : public TrainingStrategy<Scalar> {
 public:
  // `term`: the residual term, named `term_name` in errors.
  AdaptiveRefinement(const AdaptiveOptions& options, std::size_t term, std::string term_name);

  bool before_step(StrategyView<Scalar>& view) override;
  void points_drawn(std::size_t k, TermPoints& points) override;
  void between_segments(StrategyView<Scalar>& view, bool redraw) override;
  int segment_limit(bool /*reweighted*/) const override { return options_.every; }
  void metrics(std::vector<std::pair<std::string, double>>& out) const override;
  void save(io::H5Writer& file, const std::string& group) const override;
  void load(const io::H5Reader& file, const std::string& group) override;

  // The extra set, oldest point first.
  const Eigen::MatrixXd& points() const { return points_; }

 private:
  // Draws the candidates and adds the worst to the set.
  void refine(StrategyView<Scalar>& view);

  AdaptiveOptions options_;
  std::size_t term_;
  std::string term_name_;
  Eigen::MatrixXd points_;
  Eigen::Index joined_rows_ = 0;  // rows of the set behind the term's current points
};

}  // namespace nfield::solvers
