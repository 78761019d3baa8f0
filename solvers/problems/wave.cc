// SPDX-License-Identifier: MIT
//
// Wave equation: u_tt = c²Δu + f on a box of 1–3 space dimensions times a time interval
// [t0, t1] (field inputs x…, t), with initial displacement and velocity from the
// `initial` conditions and Dirichlet/Neumann conditions on the space faces.
//
//   problem: wave
//   domain: {lower: [0], upper: [1], time: [0, 1]}
//   equation:
//     speed: 2                    # c: a number, or an expression c(x, y, z, t) > 0
//     source: "0"                 # f, optional (default 0)
//     exact: "sin(pi*x)*cos(2*pi*t)"   # optional: error metrics
//     reference: finite_difference     # or {cells: 512, cfl: 0.5, snapshots: 101}: instead
//                                      # of `exact`, a computed reference for the metrics
//   conditions:
//     - {on: boundary, type: dirichlet, value: "0"}
//     - {on: initial, type: value, value: "sin(pi*x)", weight: 10}
//     - {on: initial, type: velocity, value: "0", weight: 10}
//
// The interior residual is r = u_tt − c²Δu − f (loss term "pde"). With `enforce: hard` on
// the Dirichlet and initial items, u = u0 + τ v0 + φ(x) ψ(τ)² N satisfies them exactly and
// "pde" is the only loss term (solvers/core/ansatz.h).
//
// How the second derivatives travel: a constant speed makes the wave operator one operator
// stream tr(C ∇²u) with C = diag(−c², …, −c², 1) over the axes (x…, t), so a 1D + time
// field costs 1 + 2 + 1 = 4 streams. A speed that varies in space or time cannot ride in C
// (C is the same for every point of a pass), so then the pass carries two operator streams,
// u_tt (C = e_t e_tᵀ) and Δu (C = diag(1, …, 1, 0)), and the residual weights the second by
// the per-point coefficient −c(x)² — one stream more, same residual.
//
// `reference` solves the same equation, conditions and initial data by finite differences on
// a fine grid before training (solvers/problems/wave_reference.h: the scheme, its order and
// its cost) and reports the errors against it, frame by frame as for `exact`. It needs one
// Dirichlet or Neumann item for every face and both initial items.
#include <chrono>
#include <cmath>
#include <cstdio>

#include "io/text.h"
#include "solvers/conditions/conditions.h"
#include "solvers/conditions/hard_constraints.h"
#include "solvers/problems/problems.h"
#include "solvers/problems/wave_reference.h"

namespace nfield::solvers {
namespace {

class Wave final : public Problem {
 public:
  explicit Wave(const ProblemContext& context)
      : domain_(Domain::from_config(context.root.child("domain"))) {
    if (!domain_.has_time())
      throw context.root.child("domain").error(
          "time", "the wave equation needs a time interval (domain.time: [t0, t1])");
    const io::ConfigNode equation = context.root.child("equation");
    const auto vars = domain_.expression_variables();
    const io::Expression speed = equation.get_expression("speed", vars);
    if (speed.is_constant()) {
      const double point[1] = {0.0};
      const double c = speed.evaluate(std::span<const double>(point, 0));
      equation.require("speed", std::isfinite(c) && c > 0, "expected a speed c > 0");
      constant_speed_ = c;
    } else {
      speed_ = std::make_shared<io::Expression>(speed);
    }
    source_ = std::make_shared<io::Expression>(equation.get_expression_or("source", "0", vars));
    if (equation.has("exact"))
      exact_ = std::make_shared<io::Expression>(equation.get_expression("exact", vars));
    const WaveReferenceOptions reference = reference_options(equation);
    equation.reject_unknown_keys();
    // (read_conditions rejects the empty mapping child_or_empty gives for an absent key.)
    if (context.root.has("conditions")) {
      ConditionReading reading;
      reading.allow_hard = true;
      conditions_items_ = read_conditions(context.root.child("conditions"), domain_, reading);
      ansatz_ = read_ansatz(conditions_items_, domain_, 1);
      conditions_ = condition_terms(conditions_items_, domain_);
    }
    if (equation.has("reference")) {
      WaveReferenceData data = reference_data(context.root, speed);
      data.source = *source_;
      const auto started = std::chrono::steady_clock::now();
      try {
        reference_ = std::make_shared<WaveReference>(domain_, data, reference, [](long n, long total) {
          std::printf("wave reference: step %ld/%ld\n", n, total);
          std::fflush(stdout);
        });
      } catch (const std::exception& e) {  // invalid options, or a speed ≤ 0 at a node
        throw equation.error("reference", e.what());
      }
      const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
      const auto& cells = reference_->cells();
      std::printf("wave reference: finite differences on %d", cells[0]);
      for (int a = 1; a < domain_.space_dim(); ++a) std::printf("x%d", cells[a]);
      std::printf(" cells, %ld steps of %.3g, %.1f s\n", reference_->steps(), reference_->time_step(), seconds);
    }
  }

  const Domain& domain() const override { return domain_; }

  fields::SineFrequencies default_sine_frequencies() const override {
    return fields::kPdeSineFrequencies;  // a differential equation: fields/field_config.h
  }
  std::vector<LossTerm> loss_terms() const override {
    const int d = domain_.space_dim(), n_in = domain_.input_dim(), t = domain_.time_column();
    LossTerm pde;
    pde.name = "pde";
    pde.batch_key = "interior";
    pde.spec = autodiff::StreamSpec::gradient(n_in);
    pde.sample = [this](Random& rng, Eigen::Index n) { return domain_.sample_interior(rng, n); };
    const auto source = source_;
    if (!speed_) {
      // One stream: tr(C ∇²u) = u_tt − c²Δu.
      Eigen::MatrixXd c = Eigen::MatrixXd::Zero(n_in, n_in);
      for (int a = 0; a < d; ++a) c(a, a) = -constant_speed_ * constant_speed_;
      c(t, t) = 1.0;
      const int q = pde.spec.add_operator(c);
      const int stream = autodiff::StreamLayout(pde.spec).op(q);
      pde.residual = [source, stream](const Eigen::MatrixXd& x) {
        return std::make_unique<LinearResidual>(
            std::vector<LinearResidual::Term>{{0, stream, 0, Eigen::VectorXd::Ones(1)}},
            Eigen::MatrixXd(source->evaluate(x)));
      };
    } else {
      // Two streams, u_tt and Δu, the second weighted by −c(x)² per point.
      Eigen::MatrixXd tt = Eigen::MatrixXd::Zero(n_in, n_in), lap = Eigen::MatrixXd::Zero(n_in, n_in);
      tt(t, t) = 1.0;
      for (int a = 0; a < d; ++a) lap(a, a) = 1.0;
      const int q_tt = pde.spec.add_operator(tt);
      const int q_lap = pde.spec.add_operator(lap);
      const autodiff::StreamLayout layout(pde.spec);
      const int s_tt = layout.op(q_tt), s_lap = layout.op(q_lap);
      const auto speed = speed_;
      pde.residual = [source, speed, s_tt, s_lap](const Eigen::MatrixXd& x) {
        const Eigen::VectorXd c = speed->evaluate(x);
        const Eigen::VectorXd minus_c2 = -c.array().square().matrix();
        return std::make_unique<LinearResidual>(
            std::vector<LinearResidual::Term>{{0, s_tt, 0, Eigen::VectorXd::Ones(1)},
                                              {0, s_lap, 0, minus_c2}},
            Eigen::MatrixXd(source->evaluate(x)));
      };
    }
    std::vector<LossTerm> terms{pde};
    terms.insert(terms.end(), conditions_.begin(), conditions_.end());
    return terms;
  }

  std::shared_ptr<const Ansatz> ansatz() const override { return ansatz_; }
  bool has_exact() const override { return exact_ != nullptr || reference_ != nullptr; }
  Eigen::MatrixXd exact(const Eigen::MatrixXd& x) const override {
    return reference_ ? reference_->values(x) : exact_->evaluate(x);
  }

 private:
  // `reference`: finite_difference, or a map of WaveReferenceOptions.
  static WaveReferenceOptions reference_options(const io::ConfigNode& equation) {
    WaveReferenceOptions options;
    if (!equation.has("reference")) return options;
    if (equation.has("exact")) throw equation.error("reference", "give either exact or reference, not both");
    if (!equation.has_map("reference")) {
      equation.get_choice("reference", {"finite_difference"});
      return options;
    }
    const io::ConfigNode node = equation.child("reference");
    if (node.has("cells")) options.cells = node.get_in_range("cells", 4, 1 << 20);
    options.cfl = node.get_or("cfl", options.cfl);
    node.require("cfl", options.cfl > 0 && options.cfl <= 1, "expected 0 < cfl <= 1 (the stability limit is 1)");
    if (node.has("snapshots")) options.snapshots = node.get_in_range("snapshots", 2, 1 << 20);
    node.reject_unknown_keys();
    return options;
  }

  // The reference's speed, initial data and face conditions from the config's items.
  WaveReferenceData reference_data(const io::ConfigNode& root, const io::Expression& speed) const {
    const io::ConfigNode equation = root.child("equation");
    WaveReferenceData data;
    data.speed = speed;
    data.faces.resize(2 * domain_.space_dim());
    bool has_value = false, has_velocity = false;
    for (const ConditionItem& item : conditions_items_) {
      const bool dirichlet = item.type == ConditionType::kDirichlet;
      if (!dirichlet && item.type != ConditionType::kNeumann && !item.initial)
        throw item.node.error("type", "the finite-difference reference (equation.reference) takes dirichlet, "
                                      "neumann and initial conditions only");
      const io::Expression value = item.channel_values(domain_).front();
      if (item.initial) {
        const bool is_value = item.type == ConditionType::kInitialValue;
        (is_value ? data.initial_value : data.initial_velocity) = value;
        (is_value ? has_value : has_velocity) = true;
        continue;
      }
      for (const Face& face : item.faces) {
        auto& slot = data.faces[2 * face.axis + (face.upper ? 1 : 0)];
        if (slot)
          throw item.node.error("on", "face " + face.name() + " has a condition already; the finite-difference "
                                      "reference (equation.reference) needs exactly one per face");
        slot = WaveFaceCondition{dirichlet, value};
      }
    }
    for (const Face& face : domain_.faces())
      if (!data.faces[2 * face.axis + (face.upper ? 1 : 0)])
        throw equation.error("reference", "the finite-difference reference needs a dirichlet or neumann "
                                          "condition on every face; " + face.name() + " has none");
    if (!has_value || !has_velocity)
      throw equation.error("reference", std::string("the finite-difference reference needs the initial ") +
                                            (has_value ? "velocity" : "value") +
                                            " (a condition with on: initial, type: " +
                                            (has_value ? "velocity" : "value") + ")");
    return data;
  }

  Domain domain_;
  double constant_speed_ = 0;                     // when the speed is a number
  std::shared_ptr<io::Expression> speed_;         // when it varies (else null)
  std::shared_ptr<io::Expression> source_, exact_;
  std::vector<ConditionItem> conditions_items_;
  std::vector<LossTerm> conditions_;
  std::shared_ptr<const Ansatz> ansatz_;
  std::shared_ptr<const WaveReference> reference_;  // equation.reference (else null)
};

}  // namespace

std::unique_ptr<Problem> make_wave(const ProblemContext& context) {
  return std::make_unique<Wave>(context);
}

}  // namespace nfield::solvers
