// SPDX-License-Identifier: MIT
#include "solvers/problems/problems.h"

#include <algorithm>

#include "io/text.h"
#include "solvers/problems/drawn_family.h"

namespace nfield::solvers {

void register_problems(Registry<ProblemFactory>& registry) {
  registry.add("poisson", make_poisson);
  registry.add("poisson_image", make_poisson_image);
  registry.add("wave", make_wave);
  registry.add("helmholtz", make_helmholtz);
  registry.add("eikonal", make_eikonal);
  registry.add("sdf", make_sdf);
  registry.add("occupancy", make_occupancy);
  registry.add("nerf", make_nerf);
  registry.add("autoint_1d", make_autoint_1d);
  registry.add("autoint_nerf", make_autoint_nerf);
  registry.add("fit", make_fit);
  registry.add("pde", make_pde);
}

namespace {
const std::vector<std::string> kBuiltIn = {"poisson", "poisson_image", "wave",        "helmholtz", "eikonal", "sdf", "occupancy",
                                           "nerf",    "autoint_1d",    "autoint_nerf", "fit",       "pde"};

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
  // The built-in problems that take shapes: poisson and pde (the others read
  // Domain::from_config without a folder, which refuses `geometry` without naming them).
  const io::ConfigNode domain = context.root.child_or_empty("domain");
  const std::string lower = io::to_lower(name);
  if (domain.is_map() && domain.has("geometry") && lower != "poisson" && lower != "pde" &&
      std::find(kBuiltIn.begin(), kBuiltIn.end(), lower) != kBuiltIn.end())
    throw domain.error("geometry", "problem: " + name + " takes a box domain (lower, upper); shapes "
                                   "(domain.geometry) work with problem: poisson and problem: pde");
  if (has_drawn_family(context.root)) return make_drawn_family(context, problems().at(name));
  return problems().at(name)(context);
}

std::vector<std::string> problem_names() { return problems().names(); }

}  // namespace nfield::solvers
