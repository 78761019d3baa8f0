// SPDX-License-Identifier: MIT
//
// A family of PDE instances whose equation constants are drawn from ranges (issue 28, item 5):
// any problem's `equation` keys, one draw per instance, e.g. Helmholtz with the point source
// anywhere in a box:
//
//   problem: helmholtz
//   equation:
//     complex: true
//     wavenumber: 12
//     family:
//       draw:                                  # equation keys, each {range: [lo, hi]} (a number)
//         source_center: {range: [[-0.4, -0.4], [0.4, 0.4]]}   # or [[lo…], [hi…]] (a list)
//       instances: 24                          # training instances (≥ 1)
//       held_out: 4                            # more, drawn after them, for metrics (≥ 0)
//       seed: 0
//
// A source term can be drawn as a Gaussian random field instead of a number:
//
//     draw:
//       source: {sine_series: {modes: 6, decay: 2, scale: 1, solution: exact}}
//
// f = Σ_k c_k φ_k over the Dirichlet eigenfunctions of the Laplacian on the domain's box,
// φ_k = Π_i sin(k_i π (x_i − lower_i) / L_i), k ∈ {1 … modes}^d, Δφ_k = −λ_k φ_k with
// λ_k = Σ_i (k_i π / L_i)², and c_k ~ N(0, scale² (λ_k / λ_1)^(−decay)): a smooth random field
// whose smoothness grows with `decay` (a truncated Karhunen–Loève expansion of a field with
// that spectrum). With `solution: KEY`, equation.KEY gets u = Σ_k −(c_k / λ_k) φ_k, the exact
// solution of Δu = f with u = 0 on the box's faces (Poisson's `exact`). Both are expressions
// over x, y, z of modes^d terms.
//
// Instance k's config is the file's with `equation.family` removed and each drawn key set to
// its value, uniform in its range per component (seeded: the same instances on every
// platform); the problem's own factory builds it, so every check, error and output is that
// problem's. The family (Problem::instances, HasInstances) stands for its first training
// instance, and is trained by training.meta (Reptile, solvers/run/meta_run.h) or with a latent
// code per instance (solvers/run/latent_run.h). Instances are named instance_K and
// held_out_K; ProblemInstance::values holds the drawn numbers (KEY, or KEY_i for a list).
//
// Errors: a range with lower > upper, a key drawn that the equation also sets, a drawn list
// whose bounds differ in length; all located at the key. Every instance is built once at load,
// so that a drawn value its problem refuses (a source outside the domain) is reported then, at
// the key's range, naming the instance and the value.
#pragma once

#include <memory>
#include <random>
#include <string>
#include <vector>

#include "io/config.h"
#include "solvers/core/problem.h"

namespace nfield::solvers {

// One draw of the sine series above on the box [lower, upper]: the expressions of f and u.
struct SineSeriesDraw {
  std::string field, solution;
};
SineSeriesDraw draw_sine_series(const std::vector<double>& lower, const std::vector<double>& upper, int modes,
                                double decay, double scale, std::mt19937_64& engine);

// Whether the config's equation holds a drawn family (equation.family.draw).
bool has_drawn_family(const io::ConfigNode& root);

// The family of `context`'s problem as above, each instance made by `factory`.
std::unique_ptr<Problem> make_drawn_family(const ProblemContext& context, const ProblemFactory& factory);

}  // namespace nfield::solvers
