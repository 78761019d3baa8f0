// SPDX-License-Identifier: MIT
//
// The factories of the registered problems, one per equation family (one file each).
// register_problems() in problems.cc lists them; adding an equation adds one line there.
#pragma once

#include "io/registry.h"
#include "solvers/core/problem.h"

namespace nfield::solvers {

std::unique_ptr<Problem> make_poisson(const ProblemContext& context);
std::unique_ptr<Problem> make_poisson_image(const ProblemContext& context);
std::unique_ptr<Problem> make_wave(const ProblemContext& context);
std::unique_ptr<Problem> make_helmholtz(const ProblemContext& context);
std::unique_ptr<Problem> make_eikonal(const ProblemContext& context);
std::unique_ptr<Problem> make_sdf(const ProblemContext& context);
std::unique_ptr<Problem> make_occupancy(const ProblemContext& context);
std::unique_ptr<Problem> make_nerf(const ProblemContext& context);
std::unique_ptr<Problem> make_autoint_1d(const ProblemContext& context);
std::unique_ptr<Problem> make_autoint_nerf(const ProblemContext& context);
std::unique_ptr<Problem> make_fit(const ProblemContext& context);
std::unique_ptr<Problem> make_pde(const ProblemContext& context);

void register_problems(Registry<ProblemFactory>& registry);

}  // namespace nfield::solvers
