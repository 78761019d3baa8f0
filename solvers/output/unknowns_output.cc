// SPDX-License-Identifier: MIT
#include "solvers/output/unknowns_output.h"

#include <cmath>
#include <cstdio>
#include <string>

#include "io/line_plot.h"
#include "io/png_image.h"

namespace nfield::solvers {

nlohmann::ordered_json unknowns_metrics(const UnknownConstants& unknowns, const UnknownTrajectory& trajectory) {
  nlohmann::ordered_json out = nlohmann::ordered_json::object();
  for (int i = 0; i < unknowns.count(); ++i) {
    const UnknownConstant& u = unknowns.items()[static_cast<std::size_t>(i)];
    nlohmann::ordered_json item;
    item["value"] = unknowns.value(i);
    item["initial"] = u.initial;
    if (u.truth) {
      item["true"] = *u.truth;
      item["rel_error"] = std::abs(unknowns.value(i) - *u.truth) / std::abs(*u.truth);
    }
    nlohmann::ordered_json samples = nlohmann::ordered_json::array();
    for (std::size_t s = 0; s < trajectory.steps.size(); ++s)
      samples.push_back({trajectory.steps[s], trajectory.values(static_cast<Eigen::Index>(s), i)});
    item["trajectory"] = samples;
    out[u.name] = item;
  }
  return out;
}

void write_unknowns_plot(const std::filesystem::path& path, const UnknownConstants& unknowns,
                         const UnknownTrajectory& trajectory) {
  const auto n = static_cast<Eigen::Index>(trajectory.steps.size());
  if (n < 2) return;
  Eigen::VectorXd steps(n);
  for (Eigen::Index s = 0; s < n; ++s) steps(s) = static_cast<double>(trajectory.steps[static_cast<std::size_t>(s)]);
  std::vector<io::PlotPanel> panels;
  for (int i = 0; i < unknowns.count(); ++i) {
    io::PlotPanel panel;
    // The truth first, so that the trajectory stays visible where it reaches it.
    if (const auto& truth = unknowns.items()[static_cast<std::size_t>(i)].truth)
      panel.curves.push_back({steps, Eigen::VectorXd::Constant(n, *truth), {0.95f, 0.5f, 0.1f}});
    panel.curves.push_back({steps, trajectory.values.col(i), {0.12f, 0.35f, 0.75f}});
    panels.push_back(std::move(panel));
  }
  io::write_png(path, io::plot_curves(panels, 900, 240 * unknowns.count()));
}

std::string unknowns_line(const UnknownConstants& unknowns) {
  std::string line = "unknowns:";
  char buffer[160];
  for (int i = 0; i < unknowns.count(); ++i) {
    const UnknownConstant& u = unknowns.items()[static_cast<std::size_t>(i)];
    std::snprintf(buffer, sizeof buffer, " %s %.6g", u.name.c_str(), unknowns.value(i));
    line += buffer;
    if (u.truth) {
      std::snprintf(buffer, sizeof buffer, " (true %.6g, %.3g %%)", *u.truth,
                    100 * std::abs(unknowns.value(i) - *u.truth) / std::abs(*u.truth));
      line += buffer;
    }
    if (i + 1 < unknowns.count()) line += ",";
  }
  return line;
}

}  // namespace nfield::solvers
