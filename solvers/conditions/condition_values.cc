// SPDX-License-Identifier: MIT
#include "solvers/conditions/condition_values.h"

#include "io/registry.h"
#include "io/text.h"

namespace nfield::solvers {

std::vector<io::Expression> channel_expressions(const io::ConfigNode& node, std::string_view key,
                                                const Domain& domain, int output_dim,
                                                const io::ExpressionConstants& constants) {
  std::vector<io::Expression> out;
  if (node.has_list(key)) {
    const io::ConfigNode list = node.child(key);
    node.require(key, static_cast<int>(list.size()) == output_dim,
                 "expected " + std::to_string(output_dim) + " expressions, one per output channel");
    for (std::size_t c = 0; c < list.size(); ++c) {
      const io::ConfigNode element = list.at(c);
      const std::string text = element.as<std::string>();
      try {
        out.push_back(io::Expression(text.empty() ? "0" : text, domain.expression_variables(), constants));
      } catch (const io::ExpressionError& e) {
        throw element.error(e.what());  // a config error, located at the list element
      }
    }
    return out;
  }
  io::Expression e = node.get_expression(key, domain.expression_variables(), constants);
  for (int c = 0; c < output_dim; ++c) out.push_back(c == 0 ? e : io::Expression("0", domain.expression_variables()));
  return out;
}

Eigen::MatrixXd evaluate_channels(const std::vector<io::Expression>& expressions,
                                  const Eigen::MatrixXd& points) {
  Eigen::MatrixXd out(points.rows(), static_cast<Eigen::Index>(expressions.size()));
  for (size_t c = 0; c < expressions.size(); ++c) out.col(c) = expressions[c].evaluate(points);
  return out;
}

std::vector<Face> condition_faces(const io::ConfigNode& item, const Domain& domain) {
  std::vector<std::string> names;
  if (item.has_list("on"))
    names = item.get<std::vector<std::string>>("on");
  else
    names = {item.get<std::string>("on")};
  item.require("on", !names.empty(), "expected a face name or a non-empty list of face names");
  std::vector<Face> faces;
  for (const std::string& name : names) {
    if (io::to_lower(name) == "boundary") {
      const auto all = domain.faces();
      faces.insert(faces.end(), all.begin(), all.end());
      continue;
    }
    try {
      faces.push_back(domain.face(name));
    } catch (const UnknownNameError& e) {
      throw item.error("on", std::string(e.what()) + ", or boundary, initial");
    }
  }
  return faces;
}

}  // namespace nfield::solvers
