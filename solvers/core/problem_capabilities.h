// SPDX-License-Identifier: MIT
//
// What some problems do beyond the Problem contract (solvers/core/problem.h). Each capability is a
// small interface of its own that a problem implements beside Problem; the run driver
// discovers it with capability<C>(problem) (a dynamic_cast) and calls it where it applies.
// Problem itself keeps only what every problem has (its domain, outputs, loss terms, ansatz,
// unknowns, reference and outputs), so a new equation implements nothing it does not use.
//
//   capability            implemented by        called by the driver
//   MasksError            helmholtz (PML)       error metrics on the grid (grid_output.cc)
//   TakesInputVariances   nerf                  setup, when the field's encoding reads variances
//   SamplesWithSolution   nerf, autoint_nerf,   before each draw of training points
//                         fit (the step)
//   KeepsState            autoint_nerf          every checkpoint, resume, `nfield render`
//   ReportsProgress       nerf, autoint_nerf,   the progress line, at most every 10 s
//                         fit
//   RendersViews          nerf, autoint_nerf    `nfield render`
//   HasInstances          fit (a family)        `nfield run` with training.meta (meta_run.h)
//   HasFieldBranches      pde (unknown fields   setup: the field's branches
//                         with `hidden`)
//   HasScaleTargets       fit                   setup, when the field has several scales
//
// Sampling is a pure function of the trainer's random engine and the problem's state: a
// problem whose points depend on the field in training (NeRF's occupancy grid and importance
// samples, AutoInt's sampling network) changes that state only in before_step, which the
// trainer calls with the step count before it draws, never inside the (const) draw.
#pragma once

#include <memory>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "fields/field_options.h"
#include "solvers/core/problem.h"
#include "solvers/core/solution.h"

namespace nfield::io {
class H5Writer;
class H5Reader;
}  // namespace nfield::io

namespace nfield::solvers {

class Random;

// The capability C of a problem, or null when it has none.
template <class C>
C* capability(Problem& problem) {
  return dynamic_cast<C*>(&problem);
}
template <class C>
const C* capability(const Problem& problem) {
  return dynamic_cast<const C*>(&problem);
}

// Which evaluation points count in error metrics (e.g. outside an absorbing layer).
class MasksError {
 public:
  virtual ~MasksError() = default;
  virtual Eigen::Array<bool, Eigen::Dynamic, 1> error_mask(const Eigen::MatrixXd& x) const = 0;
};
// The mask of a problem: its own, or every point.
Eigen::Array<bool, Eigen::Dynamic, 1> error_mask(const Problem& problem, const Eigen::MatrixXd& x);

// Outputs that are small networks of their own (an inverse problem's unknown fields with
// `hidden`, solvers/problems/pde_unknown_fields.h): the field's branches
// (fields/field_branches.h), its last outputs; the driver puts them into the field's options.
class HasFieldBranches {
 public:
  virtual ~HasFieldBranches() = default;
  virtual std::vector<fields::FieldBranch> field_branches() const = 0;
};

// Variances beside the inputs, for encodings that read them (integrated_positional,
// fields/integrated_positional.h): a problem that can give each point's variance per encoded
// coordinate (a radiance field: each sample's frustum Gaussian). The driver calls
// give_input_variances() once, before training, when the field's encoding reads them; from
// then on field_input_dim() counts the variance columns and every point the problem hands the
// field carries them.
class TakesInputVariances {
 public:
  virtual ~TakesInputVariances() = default;
  virtual void give_input_variances() = 0;
};

// A problem that samples where the field in training is. before_step is called with the
// steps done so far, the solution (valid until training ends) and the trainer's engine, before
// every draw of new points (each step of a first-order optimizer that draws, once per
// L-BFGS/LM stage); it is where the problem updates what its draws read.
class SamplesWithSolution {
 public:
  virtual ~SamplesWithSolution() = default;
  virtual void before_step(long step, const Solution& solution, Random& rng) = 0;
};

// What a problem learns beside the field (AutoInt's sampling network), kept in checkpoints:
// saved with every checkpoint, loaded on resume and by `nfield render`.
class KeepsState {
 public:
  virtual ~KeepsState() = default;
  virtual void save_state(io::H5Writer& file) const = 0;
  virtual void load_state(const io::H5Reader& file) = 0;
};

// How fast training goes and how big its last batches were, for a problem's progress figures.
struct TrainingRate {
  double steps_per_second = 0;
  // Per loss term, of its last batch: the points, and the groups of them (rays; 0: none).
  std::vector<Eigen::Index> points, groups;
};

// Figures for the progress line (a radiance field's PSNR on a held-out view, rays per
// second), computed at most every few seconds by the driver. Empty: none.
class ReportsProgress {
 public:
  virtual ~ReportsProgress() = default;
  virtual std::vector<std::pair<std::string, double>> progress_metrics(const OutputContext& context,
                                                                       const TrainingRate& rate) const = 0;
};

// A target per scale for a field with one output per scale (fields/field.h; BACON): the
// driver gives the scales' band limits (scales × input_dim, cycles per unit of each input)
// and the scale the outputs show; the problem's residuals then answer at_scale(s) with scale
// s's target (autodiff::StreamResidual::at_scale) and their plain evaluate with the output
// scale's.
class HasScaleTargets {
 public:
  virtual ~HasScaleTargets() = default;
  virtual void set_scale_cutoffs(const Eigen::MatrixXd& cutoffs, int output_scale) = 0;
};

// Renders views of the trained field into context.dir (`nfield render`).
class RendersViews {
 public:
  virtual ~RendersViews() = default;
  virtual void render_views(const OutputContext& context, const RenderRequest& request) const = 0;
};

// One instance of a family of problems (equation.family): its name (an image's file name)
// and the problem of that one signal.
struct ProblemInstance {
  std::string name;
  std::unique_ptr<Problem> problem;
  // A drawn family's values of this instance (solvers/problems/drawn_family.h), for metrics.
  std::vector<std::pair<std::string, double>> values{};
};

// A family of instances (equation.family, trained by training.meta:
// solvers/training/reptile.h): the training ones, or the held-out ones, each a problem of
// its own signal that trains and writes its outputs as any problem. The family problem
// itself stands for its first training instance (domain, outputs, loss terms), so that the
// field and the batch are read as for one signal.
class HasInstances {
 public:
  virtual ~HasInstances() = default;
  virtual std::vector<ProblemInstance> instances(bool held_out) const = 0;
};
// The instances of a problem; empty when it is no family.
std::vector<ProblemInstance> instances(const Problem& problem, bool held_out);

}  // namespace nfield::solvers
