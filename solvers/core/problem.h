// SPDX-License-Identifier: MIT
//
// A problem is one equation family (Poisson, Helmholtz, wave, Eikonal, …) read from the
// `equation:` and `conditions:` sections of a config. It names the loss terms a trainer
// lowers, and optionally an exact or reference solution for error metrics. Each family is
// one file in solvers/ plus one line in register_problems() (problems.cc). What only some
// problems do (render views, keep state in checkpoints, sample where the field is, mask
// their error, give input variances, report progress figures) are small interfaces of their
// own beside this one: solvers/core/problem_capabilities.h.
#pragma once

#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "fields/field_config.h"
#include "io/config.h"
#include "solvers/core/residual.h"
#include "solvers/core/solution.h"
#include "solvers/core/unknowns.h"

namespace nfield::solvers {

// What a problem writes besides the common outputs (grid, metrics).
struct OutputContext {
  using FieldStreams = Solution::Streams;
  std::filesystem::path dir;
  // Values of the trained field at points (n × output_dim), in double.
  std::function<Eigen::MatrixXd(const Eigen::MatrixXd&)> values;
  std::vector<int> grid;  // output.grid
  // Streams of the trained field at points (n × field_input_dim), in double, for outputs
  // that read derivatives (an integral field's fitted integrand).
  FieldStreams streams;
  // Relative rounding error of those values: the training scalar's epsilon.
  double epsilon = 2.220446049250313e-16;
  // A field with several scales (fields/field.h, Field::scales; bacon): how many, the one
  // `values` gives, each scale's values (n × output_dim, as `values`), and each scale's band
  // limit per input axis in cycles per unit (scales × input_dim; empty when unknown).
  int scales = 1;
  int output_scale = 0;
  std::function<Eigen::MatrixXd(const Eigen::MatrixXd&, int)> scale_values{};
  Eigen::MatrixXd scale_cutoffs{};
  // For write_outputs: training ended with a completed stage, so the field is the one that
  // the last reported_error evaluated, and a problem may reuse what it evaluated there.
  bool field_as_last_reported = false;
};

// What `nfield render` asks of a problem whose field renders images: the cameras of a
// transforms.json (its images, when present, give PSNRs), or a turntable around the scene.
struct RenderRequest {
  std::filesystem::path poses;    // empty: a turntable
  int turntable_frames = 36;      // ≥ 1
  double elevation_degrees = 30;  // of the turntable's cameras above the horizontal plane
};

class Ansatz;
class Problem;

class Problem {
 public:
  virtual ~Problem() = default;
  virtual const Domain& domain() const = 0;
  // The field's inputs: the domain's coordinates, or more (a radiance field also takes the
  // ray direction).
  virtual int field_input_dim() const { return domain().input_dim(); }
  virtual int output_dim() const { return 1; }
  virtual std::vector<std::string> output_names() const { return {"u"}; }
  // first_omega and hidden_omega of a field whose config names none: SIREN's 30 and 30 for
  // the fits of signals and surfaces, fields::kPdeSineFrequencies (10 and 1) for problems that
  // solve a differential equation (why: fields/field_config.h, SineFrequencies).
  virtual fields::SineFrequencies default_sine_frequencies() const {
    return fields::kSignalSineFrequencies;
  }
  virtual std::vector<LossTerm> loss_terms() const = 0;
  // The loss term whose residual is written on the output grid (-1: none).
  virtual int residual_term() const { return 0; }
  // Hard conditions: the field's output is u = A + D·N (solvers/core/ansatz.h); loss
  // terms and outputs see u. Null when every condition is soft.
  virtual std::shared_ptr<const Ansatz> ansatz() const { return nullptr; }

  // An inverse problem's unknown constants (solvers/core/unknowns.h), trained with the field; the
  // problem's residuals read their current values. Null: none.
  virtual std::shared_ptr<UnknownConstants> unknowns() const { return nullptr; }

  // A parametric field (Domain::parameters, solvers/core/domain.h): the parameter values its grid
  // outputs and errors are evaluated at, each parameter_count() long (the held-out values of
  // the config). Default: each range's middle; empty when the domain has no parameters.
  virtual std::vector<Eigen::VectorXd> held_out_parameters() const;

  virtual bool has_exact() const { return false; }
  // Exact or reference solution at x (n × output_dim).
  virtual Eigen::MatrixXd exact(const Eigen::MatrixXd& x) const;

  // The rel. L2 error of the quantity the problem reports, on the output grid, from the
  // trained field's values; nullopt: that error is the grid's comparison of the network
  // output with exact() (or there is none). For problems whose network output is not the
  // reported quantity (the factored Eikonal gives τ, the error is the travel time's). Called
  // after every training stage; write_outputs reports the same number after the last.
  virtual std::optional<double> reported_error(const OutputContext&) const { return std::nullopt; }

  // Whether the field is written on the output grid over the domain (solution.vti and its
  // PNG, grid errors): false for fields whose inputs are not the domain's coordinates.
  virtual bool writes_grid_outputs() const { return true; }

  // Extra metrics (added to metrics.json) and files after training.
  virtual void write_outputs(const OutputContext& context, std::vector<std::pair<std::string, double>>& metrics) const;
};

struct ProblemContext {
  io::ConfigNode root;               // the whole config
  std::filesystem::path config_dir;  // relative data paths resolve here
};

using ProblemFactory = std::function<std::unique_ptr<Problem>(const ProblemContext&)>;

// Adds a problem family that `problem: NAME` then selects, from code outside the library
// (an application's own equation): call before loading configs, from one thread. Throws
// std::logic_error when NAME (case-insensitive) is taken.
void register_problem(std::string_view name, ProblemFactory factory);

// The problem named by `problem:`; ConfigError lists the valid names.
std::unique_ptr<Problem> make_problem(const ProblemContext& context);
std::vector<std::string> problem_names();

}  // namespace nfield::solvers
