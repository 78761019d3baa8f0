// SPDX-License-Identifier: MIT
//
// The trainer's side of an inverse problem's unknown constants (solvers/core/unknowns.h): the
// raw values ρ ride at the tail of the field's θ, so every optimizer steps them; this class
// keeps the problem's UnknownConstants in step with the θ being evaluated and adds their
// gradient to θ's tail:
//
//   before a pass at θ      set_raw(θ tail): the residuals read c = g(ρ) while they run;
//   after it                ∂L/∂ρᵢ = (Σ over the blocks of r̄ · ∂r/∂cᵢ) · g'(ρᵢ), the block
//                           sums gathered by ExtraGradient in block order (solvers/core/residual.h)
//                           and added into the gradient's tail before the ranks' allreduce,
//                           so MPI sums them with the field's gradient.
//
// It also keeps the trajectory of the values (every `every()` steps, for metrics.json and
// the plot) and writes ρ and the trajectory into the checkpoint: a resumed run continues with
// the same ρ (the field's own checkpoint holds only the network's part) and Adam's moments,
// which cover all of θ, come back with the optimizer's state, so it ends bit for bit as an
// uninterrupted one.
#pragma once

#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "fields/field.h"
#include "io/hdf5_file.h"
#include "solvers/core/residual.h"
#include "solvers/core/unknowns.h"

namespace nfield::solvers {

// One sample of the trajectory: the global step and the values then.
struct UnknownSample {
  long step = 0;
  std::vector<double> values;
};

template <typename Scalar>
class TrainedUnknowns {
 public:
  // Appends the unknowns' initial ρ to the field's θ (unless it has them already). Null
  // `unknowns`: a run without any (every method is then a no-op).
  TrainedUnknowns(std::shared_ptr<UnknownConstants> unknowns, fields::Field<Scalar>& field, long total_steps);

  bool active() const { return unknowns_ != nullptr; }
  const UnknownConstants* constants() const { return unknowns_.get(); }
  // Where blocks add their gradient with respect to c (null without unknowns).
  ExtraGradient* gradient_sink() { return active() ? &sink_ : nullptr; }

  // Before a pass at θ (parameter_count values).
  void before_pass(const Scalar* theta);
  // After it: the gathered gradient, chained to ρ, added into the tail of `gradient`.
  void add_gradient(Scalar* gradient);
  // After a step: the values at the field's θ, sampled into the trajectory when due.
  void after_step(long step);
  // Progress figures: name → current value.
  void progress(std::vector<std::pair<std::string, double>>& extras) const;
  int every() const { return every_; }
  const std::vector<UnknownSample>& trajectory() const { return trajectory_; }

  void save(io::H5Writer& file) const;
  void load(const io::H5Reader& file);

 private:
  std::shared_ptr<UnknownConstants> unknowns_;
  fields::Field<Scalar>& field_;
  ExtraGradient sink_;
  int every_ = 1;
  std::vector<UnknownSample> trajectory_;
};

}  // namespace nfield::solvers
