// SPDX-License-Identifier: MIT
#include "solvers/problems/allen_cahn_reference.h"

#include <unsupported/Eigen/FFT>

#include <algorithm>
#include <cmath>
#include <complex>
#include <numbers>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace nfield::solvers {
namespace {

using Complex = std::complex<double>;
using Spectrum = std::vector<Complex>;
constexpr double kPi = std::numbers::pi;

[[noreturn]] void invalid(const std::string& field, double value, const std::string& rule) {
  std::ostringstream out;
  out << "AllenCahnOptions." << field << " = " << value << ": " << rule;
  throw std::invalid_argument(out.str());
}

// The ETDRK4 coefficients of one step h for the diagonal L (Kassam & Trefethen 2005, eq. 2.5
// and §3): E = e^{hL}, E2 = e^{hL/2}, Q, f1, f2, f3, each a mean over a circle around hL.
struct Etdrk4 {
  std::vector<double> e, e2, q, f1, f2, f3;

  Etdrk4(const std::vector<double>& l, double h) {
    constexpr int kCircle = 32;
    const size_t n = l.size();
    e.resize(n), e2.resize(n), q.resize(n), f1.resize(n), f2.resize(n), f3.resize(n);
    for (size_t m = 0; m < n; ++m) {
      e[m] = std::exp(h * l[m]);
      e2[m] = std::exp(h * l[m] / 2);
      Complex sq = 0, s1 = 0, s2 = 0, s3 = 0;
      for (int j = 1; j <= kCircle; ++j) {
        const Complex z = h * l[m] + std::exp(Complex(0, kPi * (j - 0.5) / kCircle));
        const Complex ez = std::exp(z), z3 = z * z * z;
        sq += (std::exp(z / 2.0) - 1.0) / z;
        s1 += (-4.0 - z + ez * (4.0 - 3.0 * z + z * z)) / z3;
        s2 += (2.0 + z + ez * (z - 2.0)) / z3;
        s3 += (-4.0 - 3.0 * z - z * z + ez * (4.0 - z)) / z3;
      }
      q[m] = h * sq.real() / kCircle;
      f1[m] = h * s1.real() / kCircle;
      f2[m] = h * s2.real() / kCircle;
      f3[m] = h * s3.real() / kCircle;
    }
  }
};

// The semi-linear system in Fourier space: L diagonal, N(v) = F(ρ(u − u³)), u = F⁻¹v.
class AllenCahnSystem {
 public:
  explicit AllenCahnSystem(const AllenCahnOptions& o) : n_(static_cast<size_t>(o.modes)), rho_(o.reaction) {
    linear_.resize(n_);
    for (size_t j = 0; j < n_; ++j) {
      const double m = j < n_ / 2 ? static_cast<double>(j) : static_cast<double>(j) - static_cast<double>(n_);
      linear_[j] = -o.diffusion * (kPi * m) * (kPi * m);
    }
  }
  const std::vector<double>& linear() const { return linear_; }

  Spectrum nonlinear(const Spectrum& v) {
    fft_.inv(u_, v);
    for (Complex& u : u_) {
      const double r = u.real();
      u = rho_ * (r - r * r * r);
    }
    Spectrum out;
    fft_.fwd(out, u_);
    return out;
  }
  Spectrum forward(const std::vector<double>& u) {
    std::vector<Complex> c(u.begin(), u.end());
    Spectrum out;
    fft_.fwd(out, c);
    return out;
  }
  std::vector<double> inverse(const Spectrum& v) {
    fft_.inv(u_, v);
    std::vector<double> out(n_);
    for (size_t j = 0; j < n_; ++j) out[j] = u_[j].real();
    return out;
  }

 private:
  size_t n_;
  double rho_;
  std::vector<double> linear_;
  Eigen::FFT<double> fft_;
  Spectrum u_;
};

// One ETDRK4 step of v in place.
void step(AllenCahnSystem& system, const Etdrk4& c, Spectrum& v) {
  const size_t n = v.size();
  const Spectrum nv = system.nonlinear(v);
  Spectrum a(n), b(n), d(n);
  for (size_t m = 0; m < n; ++m) a[m] = c.e2[m] * v[m] + c.q[m] * nv[m];
  const Spectrum na = system.nonlinear(a);
  for (size_t m = 0; m < n; ++m) b[m] = c.e2[m] * v[m] + c.q[m] * na[m];
  const Spectrum nb = system.nonlinear(b);
  for (size_t m = 0; m < n; ++m) d[m] = c.e2[m] * a[m] + c.q[m] * (2.0 * nb[m] - nv[m]);
  const Spectrum nd = system.nonlinear(d);
  for (size_t m = 0; m < n; ++m)
    v[m] = c.e[m] * v[m] + nv[m] * c.f1[m] + 2.0 * (na[m] + nb[m]) * c.f2[m] + nd[m] * c.f3[m];
}

}  // namespace

void AllenCahnOptions::validate() const {
  if (!(std::isfinite(diffusion) && diffusion > 0)) invalid("diffusion", diffusion, "expected a finite ε > 0");
  if (!(std::isfinite(reaction) && reaction >= 0)) invalid("reaction", reaction, "expected a finite ρ >= 0");
  if (modes < 16 || modes > 65536 || modes % 2 != 0) invalid("modes", modes, "expected an even count in [16, 65536]");
  if (!(std::isfinite(t_end) && t_end > 0)) invalid("t_end", t_end, "expected a finite T > 0");
  if (!(std::isfinite(dt) && dt > 0 && dt <= t_end)) invalid("dt", dt, "expected a step in (0, t_end]");
  if (snapshots < 4 || snapshots > 100000) invalid("snapshots", snapshots, "expected a count in [4, 100000]");
}

AllenCahnReference::AllenCahnReference(const AllenCahnOptions& options) : options_(options) {
  options_.validate();
  const int n = options_.modes, frames = options_.snapshots;
  AllenCahnSystem system(options_);
  std::vector<double> u0(static_cast<size_t>(n));
  for (int j = 0; j < n; ++j) u0[static_cast<size_t>(j)] = node(j) * node(j) * std::cos(kPi * node(j));
  Spectrum v = system.forward(u0);
  const double interval = options_.t_end / (frames - 1);
  const int steps = static_cast<int>(std::ceil(interval / options_.dt - 1e-9));
  const Etdrk4 coefficients(system.linear(), interval / steps);
  values_.resize(frames, n);
  coefficients_.resize(frames, n);
  for (int k = 0; k < frames; ++k) {
    if (k > 0)
      for (int s = 0; s < steps; ++s) step(system, coefficients, v);
    const std::vector<double> u = system.inverse(v);
    for (int j = 0; j < n; ++j) {
      values_(k, j) = u[static_cast<size_t>(j)];
      coefficients_(k, j) = v[static_cast<size_t>(j)];
    }
  }
}

double AllenCahnReference::time(int k) const { return options_.t_end * k / (options_.snapshots - 1); }
double AllenCahnReference::node(int j) const { return -1.0 + 2.0 * j / options_.modes; }

// (1/N) Σ_m v_m e^{iπm(x+1)}, real part; the Nyquist mode as its cosine.
double AllenCahnReference::interpolate_in_x(int snapshot, double x) const {
  const int n = options_.modes;
  const double theta = kPi * (x + 1);
  const Complex z = std::polar(1.0, theta);
  Complex w = z;  // e^{imθ}, by rotation (rounding grows like m ε, harmless at N ≤ 65536)
  double sum = coefficients_(snapshot, 0).real();
  for (int m = 1; m < n / 2; ++m, w *= z)
    sum += 2 * (coefficients_(snapshot, m) * w).real();  // with its conjugate at N − m
  sum += coefficients_(snapshot, n / 2).real() * std::cos((n / 2) * theta);
  return sum / n;
}

double AllenCahnReference::operator()(double x, double t) const {
  if (!std::isfinite(x) || !(t >= 0 && t <= options_.t_end))
    throw std::invalid_argument("AllenCahnReference: needs a finite x and t in [0, " + std::to_string(options_.t_end) +
                                "], got x = " + std::to_string(x) + ", t = " + std::to_string(t));
  const int frames = options_.snapshots;
  const double s = t / options_.t_end * (frames - 1);
  const int first = std::clamp(static_cast<int>(std::floor(s)) - 1, 0, frames - 4);
  double u = 0;
  for (int a = 0; a < 4; ++a) {
    double weight = 1;
    for (int b = 0; b < 4; ++b)
      if (b != a) weight *= (s - (first + b)) / static_cast<double>(a - b);
    u += weight * interpolate_in_x(first + a, x);
  }
  return u;
}

Eigen::VectorXd AllenCahnReference::evaluate(const Eigen::MatrixXd& points) const {
  if (points.cols() != 2) throw std::invalid_argument("AllenCahnReference::evaluate: expected n x 2 points (x, t)");
  Eigen::VectorXd u(points.rows());
#pragma omp parallel for schedule(dynamic, 64)
  for (Eigen::Index i = 0; i < points.rows(); ++i) u(i) = (*this)(points(i, 0), points(i, 1));
  return u;
}

}  // namespace nfield::solvers
