// SPDX-License-Identifier: MIT
#include "solvers/conditions/hard_constraints.h"

#include <ceres/jet.h>

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <type_traits>

#include "io/text.h"
#include "solvers/conditions/condition_values.h"
#include "solvers/conditions/condition_list.h"

namespace nfield::solvers {

namespace {

std::vector<std::string> texts(const std::vector<io::Expression>& e) {
  std::vector<std::string> out;
  for (const auto& x : e) out.push_back(x.text());
  return out;
}

// Largest |a − b| over points, with the point where it occurs.
double max_mismatch(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b, Eigen::Index& where) {
  Eigen::Index col;
  return (a - b).cwiseAbs().maxCoeff(&where, &col);
}

std::string point_text(const Eigen::MatrixXd& x, Eigen::Index r) {
  std::ostringstream s;
  s << "(";
  for (Eigen::Index c = 0; c < x.cols(); ++c) s << (c ? ", " : "") << x(r, c);
  s << ")";
  return s.str();
}

}  // namespace

namespace {

// The hard items of a condition list, merged: one Dirichlet part (faces and named parts,
// all with the same value) and at most one initial value and one initial velocity.
struct HardItems {
  std::optional<Ansatz::Dirichlet> dirichlet;
  std::optional<io::ConfigNode> dirichlet_item, value_item, velocity_item;
  std::vector<io::Expression> u0, v0;
  double time_scale = 0;

  void add_initial(const ConditionItem& item, std::vector<io::Expression> values) {
    const bool value = item.type == ConditionType::kInitialValue;
    auto& slot = value ? value_item : velocity_item;
    if (slot) throw item.node.error("enforce", std::string("a second hard initial ") + (value ? "value" : "velocity") + " condition");
    slot = item.node;
    (value ? u0 : v0) = std::move(values);
    if (value) time_scale = item.time_scale;
  }

  void add_dirichlet(const ConditionItem& item, std::vector<io::Expression> values) {
    if (!dirichlet) {
      dirichlet = Ansatz::Dirichlet{{}, std::move(values)};
      dirichlet->fade = item.fade;
      dirichlet->saturate = item.saturate;
      dirichlet_item = item.node;
    } else if (item.fade != dirichlet->fade || item.saturate != dirichlet->saturate) {
      throw item.node.error(item.fade != dirichlet->fade ? "fade" : "saturate",
                            "hard Dirichlet conditions must all carry the same `fade` and `saturate` (the "
                            "hard one at line " +
                                std::to_string(dirichlet_item->mark().line + 1) + " differs)");
    } else if (texts(values) != texts(dirichlet->values)) {
      throw item.node.error("value", "hard Dirichlet conditions must all carry the same value (this "
                                     "one differs from the hard one at line " +
                                         std::to_string(dirichlet_item->mark().line + 1) +
                                         "); make one of them soft");
    }
    if (item.parts) {
      // The union of the named parts; `boundary` (no names) is all of them.
      if (!dirichlet->parts) dirichlet->parts = *item.parts;
      else if (item.parts->parts.empty() || dirichlet->parts->parts.empty()) dirichlet->parts->parts.clear();
      else
        for (int p : item.parts->parts)
          if (std::find(dirichlet->parts->parts.begin(), dirichlet->parts->parts.end(), p) ==
              dirichlet->parts->parts.end())
            dirichlet->parts->parts.push_back(p);
    }
    for (const Face& f : item.faces)
      if (std::none_of(dirichlet->faces.begin(), dirichlet->faces.end(),
                       [&](const Face& g) { return g.axis == f.axis && g.upper == f.upper; }))
        dirichlet->faces.push_back(f);
  }
};

// u = u0 + τ v0 + φ (τ/T)² N equals g on the faces only for compatible data: g constant in t,
// u0 = g and v0 = 0 on the hard faces at t0 (checked at 256 points drawn there).
void check_compatible(const HardItems& hard, const Domain& domain) {
  for (const auto& g : hard.dirichlet->values)
    if (g.uses("t"))
      throw hard.dirichlet_item->error(
          "value", "a hard Dirichlet value that depends on t cannot be combined with hard "
                   "initial conditions; make one of them soft");
  Random rng(0);
  Eigen::MatrixXd x = hard.dirichlet->parts ? domain.sample_boundary(*hard.dirichlet->parts, rng, 256).points
                                            : domain.sample_faces(hard.dirichlet->faces, rng, 256);
  x.col(domain.time_column()).setConstant(domain.time().first);
  const Eigen::MatrixXd g = evaluate_channels(hard.dirichlet->values, x);
  const Eigen::MatrixXd a = evaluate_channels(hard.u0, x);
  Eigen::Index where = 0;
  const double tol = 1e-8 * (1.0 + std::max(g.cwiseAbs().maxCoeff(), a.cwiseAbs().maxCoeff()));
  const double miss = max_mismatch(a, g, where);
  if (!(miss <= tol))
    throw hard.value_item->error("value", "the hard initial value must equal the hard Dirichlet value "
                                          "on the hard faces at t0; they differ by " +
                                              std::to_string(miss) + " at " + point_text(x, where));
  if (hard.velocity_item) {
    const Eigen::MatrixXd v = evaluate_channels(hard.v0, x);
    const double vmiss = max_mismatch(v, Eigen::MatrixXd::Zero(v.rows(), v.cols()), where);
    if (!(vmiss <= 1e-8 * (1.0 + v.cwiseAbs().maxCoeff())))
      throw hard.velocity_item->error("value", "the hard initial velocity must vanish on the hard "
                                               "Dirichlet faces (their value is constant in t); it is " +
                                                   std::to_string(vmiss) + " at " + point_text(x, where));
  }
}

}  // namespace

std::shared_ptr<const Ansatz> read_ansatz(const std::vector<ConditionItem>& items, const Domain& domain,
                                          int output_dim) {
  HardItems hard;
  for (const ConditionItem& item : items) {
    if (!item.hard) continue;
    if (item.initial)
      hard.add_initial(item, item.channel_values(domain));
    else
      hard.add_dirichlet(item, item.channel_values(domain));
  }
  if (hard.velocity_item && !hard.value_item)
    throw hard.velocity_item->error("enforce",
                                    "a hard initial velocity needs the initial value hard too");
  std::optional<Ansatz::Initial> initial;
  if (hard.value_item) {
    initial = Ansatz::Initial{hard.u0, std::nullopt, hard.time_scale};
    if (hard.velocity_item) initial->velocity = hard.v0;
  }
  if (!hard.dirichlet && !initial) return nullptr;
  if (hard.dirichlet && initial) check_compatible(hard, domain);
  return std::make_shared<const Ansatz>(domain, output_dim, std::move(hard.dirichlet), std::move(initial));
}

}  // namespace nfield::solvers
