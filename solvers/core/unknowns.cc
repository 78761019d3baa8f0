// SPDX-License-Identifier: MIT
#include "solvers/core/unknowns.h"

#include <cmath>
#include <stdexcept>

#include "io/text.h"

namespace nfield::solvers {

void UnknownConstant::validate() const {
  const auto reject = [&](const std::string& field, double v, const std::string& rule) {
    throw std::invalid_argument("constants." + name + "." + field + " = " + io::format_number(v) + ": " + rule);
  };
  if (!std::isfinite(initial)) reject("initial", initial, "must be finite");
  if (positive && bounds) reject("positive", 1, "give positive or bounds, not both");
  if (positive && !(initial > 0)) reject("initial", initial, "must be > 0 with positive: true");
  if (bounds) {
    if (!(bounds->first < bounds->second)) reject("bounds", bounds->first, "the lower bound must be below the upper");
    if (!(initial > bounds->first && initial < bounds->second))
      reject("initial", initial, "must lie strictly inside bounds");
  }
  if (lr && !(*lr > 0)) reject("lr", *lr, "must be > 0");
  if (truth && !std::isfinite(*truth)) reject("true", *truth, "must be finite");
}

double UnknownConstant::value(double raw) const {
  if (positive) return std::exp(raw);
  if (bounds) return bounds->first + (bounds->second - bounds->first) / (1 + std::exp(-raw));
  return raw;
}

double UnknownConstant::derivative(double raw) const {
  if (positive) return std::exp(raw);
  if (bounds) {
    const double s = 1 / (1 + std::exp(-raw));
    return (bounds->second - bounds->first) * s * (1 - s);
  }
  return 1;
}

double UnknownConstant::raw(double value) const {
  if (positive) return std::log(value);
  if (bounds) {
    const double s = (value - bounds->first) / (bounds->second - bounds->first);
    return std::log(s / (1 - s));
  }
  return value;
}

UnknownConstants::UnknownConstants(std::vector<UnknownConstant> items) : items_(std::move(items)) {
  for (const UnknownConstant& u : items_) u.validate();
  raw_ = initial_raw();
  values_.resize(items_.size());
  set_raw(raw_.data());
}

int UnknownConstants::index(const std::string& name) const {
  for (int i = 0; i < count(); ++i)
    if (items_[static_cast<std::size_t>(i)].name == name) return i;
  return -1;
}

std::vector<double> UnknownConstants::initial_raw() const {
  std::vector<double> raw;
  for (const UnknownConstant& u : items_) raw.push_back(u.raw(u.initial));
  return raw;
}

}  // namespace nfield::solvers
