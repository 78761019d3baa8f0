// SPDX-License-Identifier: MIT
//
// Unknown constants of an inverse problem: numbers of the equation (a viscosity ν, a
// wavenumber k) that are trained with the field instead of given.
//
//   constants:
//     nu: {unknown: true, initial: 0.05, positive: true, true: 0.00318}
//     k:  {unknown: true, initial: 3, bounds: [1, 10], lr: 1.0e-2}
//
// How they join the parameters. The optimizers see one flat vector θ (fields/field.h); a
// run with q unknowns appends q raw values ρ to it (Field::set_extra_parameters), so Adam,
// L-BFGS and Levenberg–Marquardt, the checkpoints of the optimizer state and the MPI
// allreduce of the gradient take them with no case of their own. The constant an expression
// reads is c = g(ρ):
//
//   free                 c = ρ
//   positive: true       c = exp(ρ)                   (log parametrisation)
//   bounds: [a, b]       c = a + (b − a)·σ(ρ),  σ(ρ) = 1/(1 + e^−ρ)
//
// Why log rather than softplus for `positive`: the constants such problems identify span
// decades (λ₂ = 0.01/π from an initial 0.05), and a step of Adam in ρ = log c is a relative
// change of c whatever its size, so one learning rate serves 3e-3 and 300 alike; softplus is
// linear above a few units and as slow as the free form near 0, where viscosities live.
// A bound keeps c inside (a, b) for every ρ; its slope σ' vanishes near the ends, so an
// initial value near a bound trains slowly (the header's pitfall: bound loosely).
//
// The trainer writes the current ρ (the optimizer's θ tail, trial points of a line search
// included) with set_raw before every evaluation of the loss; residuals read value(i) while
// they run (a read-only shared state during the threads' passes) and report ∂r/∂c, which the
// trainer chains with dc/dρ (raw_derivative). `lr` is an Adam learning rate of the
// constant's own: the stage's rate times lr/stage.lr through the stage's schedule.
#pragma once

#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace nfield::solvers {

struct UnknownConstant {
  std::string name;
  double initial = 1;
  bool positive = false;
  std::optional<std::pair<double, double>> bounds;  // open interval (lower, upper)
  std::optional<double> truth;                      // `true:` for reporting only
  std::optional<double> lr;                         // Adam's own rate (nullopt: the stage's)

  // Throws std::invalid_argument naming the field, its value and the rule.
  void validate() const;
  // c = g(ρ), dc/dρ, and ρ = g⁻¹(c) (see the header).
  double value(double raw) const;
  double derivative(double raw) const;
  double raw(double value) const;
};

class UnknownConstants {
 public:
  explicit UnknownConstants(std::vector<UnknownConstant> items);

  int count() const { return static_cast<int>(items_.size()); }
  const std::vector<UnknownConstant>& items() const { return items_; }
  int index(const std::string& name) const;  // -1: no such unknown

  // ρ of every unknown at its initial value.
  std::vector<double> initial_raw() const;
  // The current ρ (count() values; the optimizer's θ tail), in double.
  template <typename Scalar>
  void set_raw(const Scalar* raw) {
    for (int i = 0; i < count(); ++i) {
      raw_[static_cast<std::size_t>(i)] = static_cast<double>(raw[i]);
      values_[static_cast<std::size_t>(i)] = items_[static_cast<std::size_t>(i)].value(raw_[static_cast<std::size_t>(i)]);
    }
  }
  // The current c of unknown i, as residuals read it.
  double value(int i) const { return values_[static_cast<std::size_t>(i)]; }
  const std::vector<double>& values() const { return values_; }
  double raw_derivative(int i) const { return items_[static_cast<std::size_t>(i)].derivative(raw_[static_cast<std::size_t>(i)]); }

 private:
  std::vector<UnknownConstant> items_;
  std::vector<double> raw_, values_;
};

}  // namespace nfield::solvers
