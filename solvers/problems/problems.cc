// SPDX-License-Identifier: MIT
#include "solvers/problems/problems.h"

namespace nfield::solvers {

void register_problems(Registry<ProblemFactory>& registry) {
  registry.add("poisson", make_poisson);
  registry.add("poisson_image", make_poisson_image);
  registry.add("wave", make_wave);
  registry.add("helmholtz", make_helmholtz);
  registry.add("eikonal", make_eikonal);
  registry.add("sdf", make_sdf);
  registry.add("nerf", make_nerf);
  registry.add("autoint_1d", make_autoint_1d);
  registry.add("autoint_nerf", make_autoint_nerf);
  registry.add("fit", make_fit);
  registry.add("pde", make_pde);
}

namespace {
Registry<ProblemFactory>& problems() {
  static Registry<ProblemFactory> registry = [] {
    Registry<ProblemFactory> r("problem");
    register_problems(r);
    return r;
  }();
  return registry;
}
}  // namespace

void register_problem(std::string_view name, ProblemFactory factory) {
  problems().add(name, std::move(factory));
}

std::unique_ptr<Problem> make_problem(const ProblemContext& context) {
  const std::string name = context.root.get<std::string>("problem");
  if (!problems().contains(name))
    throw context.root.error("problem", "unknown problem '" + name + "' (valid: " +
                                            problems().joined_names() + ")");
  return problems().at(name)(context);
}

std::vector<std::string> problem_names() { return problems().names(); }

}  // namespace nfield::solvers
