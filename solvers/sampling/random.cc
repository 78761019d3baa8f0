// SPDX-License-Identifier: MIT
#include "solvers/sampling/random.h"

#include <boost/random/sobol.hpp>

#include <cmath>
#include <sstream>
#include <stdexcept>

namespace nfield::solvers {
namespace {

constexpr int kPrimes[UnitSequence::kMaxDimension] = {2,  3,  5,  7,  11, 13, 17, 19,
                                                      23, 29, 31, 37, 41, 43, 47, 53};

double radical_inverse(std::uint64_t i, int base) {
  const double inverse = 1.0 / base;
  double f = inverse, result = 0;
  for (; i > 0; i /= base, f *= inverse) result += static_cast<double>(i % base) * f;
  return result;
}

}  // namespace

std::uint64_t mix(std::uint64_t z) {
  z += 0x9E3779B97F4A7C15ull;
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

const std::vector<std::string>& sampler_names() {
  static const std::vector<std::string> names{"uniform", "sobol", "halton"};
  return names;
}

Eigen::MatrixXd unit_points(Random& rng, Eigen::Index n, int dim) {
  if (rng.sequence()) return rng.sequence()->next(n, dim);
  Eigen::MatrixXd u(n, dim);
  // Row by row: the order the engine has always been drawn in, so uniform runs repeat.
  for (Eigen::Index r = 0; r < n; ++r)
    for (int c = 0; c < dim; ++c) u(r, c) = uniform01(rng);
  return u;
}

struct UnitSequence::Stream {
  int dim = 0;
  std::uint64_t count = 0;
  std::unique_ptr<boost::random::sobol> sobol;  // sobol only
  std::vector<std::uint64_t> masks;              // sobol: digital shift per coordinate
  std::vector<double> shifts;                    // halton: rotation per coordinate
  std::uint64_t offset = 0;                      // halton: first index
};

UnitSequence::UnitSequence(std::string kind, std::uint64_t seed) : kind_(std::move(kind)), seed_(seed) {
  if (kind_ != "sobol" && kind_ != "halton")
    throw std::invalid_argument("UnitSequence: unknown kind '" + kind_ + "' (sobol, halton)");
}
UnitSequence::~UnitSequence() = default;
UnitSequence::UnitSequence(UnitSequence&&) noexcept = default;
UnitSequence& UnitSequence::operator=(UnitSequence&&) noexcept = default;

UnitSequence::Stream& UnitSequence::stream(int dim) {
  if (dim < 1 || dim > kMaxDimension)
    throw std::invalid_argument("UnitSequence: dimension " + std::to_string(dim) +
                                " outside 1.." + std::to_string(kMaxDimension));
  auto& slot = streams_[dim];
  if (!slot) {
    slot = std::make_unique<Stream>();
    slot->dim = dim;
    std::mt19937_64 engine(mix(seed_ ^ mix(static_cast<std::uint64_t>(dim))));
    if (kind_ == "sobol") {
      slot->sobol = std::make_unique<boost::random::sobol>(dim);
      for (int j = 0; j < dim; ++j) slot->masks.push_back(engine());
    } else {
      for (int j = 0; j < dim; ++j) slot->shifts.push_back(static_cast<double>(engine() >> 11) * 0x1.0p-53);
      slot->offset = 1 + (engine() >> 44);  // in [1, 2^20]: index 0 is the origin in every base
    }
  }
  return *slot;
}

Eigen::MatrixXd UnitSequence::next(Eigen::Index n, int dim) {
  Stream& s = stream(dim);
  Eigen::MatrixXd u(n, dim);
  for (Eigen::Index r = 0; r < n; ++r) {
    if (s.sobol) {
      for (int j = 0; j < dim; ++j)
        u(r, j) = static_cast<double>(((*s.sobol)() ^ s.masks[j]) >> 11) * 0x1.0p-53;
    } else {
      const std::uint64_t index = s.offset + s.count;
      for (int j = 0; j < dim; ++j) {
        double v = radical_inverse(index, kPrimes[j]) + s.shifts[j];
        if (v >= 1.0) v -= 1.0;
        u(r, j) = v < 1.0 ? v : std::nextafter(1.0, 0.0);
      }
    }
    ++s.count;
  }
  return u;
}

std::map<int, std::uint64_t> UnitSequence::counts() const {
  std::map<int, std::uint64_t> out;
  for (const auto& [dim, s] : streams_) out[dim] = s->count;
  return out;
}

void UnitSequence::set_counts(const std::map<int, std::uint64_t>& counts) {
  streams_.clear();
  for (const auto& [dim, count] : counts) {
    Stream& s = stream(dim);
    s.count = count;
    // Boost's seed(k) positions the engine so that the next vector drawn is vector k.
    if (s.sobol) s.sobol->seed(count);
  }
}

std::string UnitSequence::state() const {
  std::ostringstream os;
  for (const auto& [dim, count] : counts()) os << dim << ':' << count << ' ';
  return os.str();
}

void UnitSequence::set_state(const std::string& text) {
  std::istringstream is(text);
  std::map<int, std::uint64_t> counts;
  int dim;
  char colon;
  std::uint64_t count;
  while (is >> dim >> colon >> count) {
    if (colon != ':') throw std::invalid_argument("UnitSequence: bad state '" + text + "'");
    counts[dim] = count;
  }
  if (!is.eof()) throw std::invalid_argument("UnitSequence: bad state '" + text + "'");
  set_counts(counts);
}

}  // namespace nfield::solvers
