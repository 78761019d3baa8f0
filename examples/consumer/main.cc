// SPDX-License-Identifier: MIT
//
// Builds a small SIREN u: R² → R from the installed nfield, evaluates u, ∇u and Δu in one
// pass of derivative streams, and checks Δu against central differences of u.
#include <cmath>
#include <cstdio>

#include "autodiff/streams.h"
#include "fields/field.h"

static_assert(EIGEN_MAX_ALIGN_BYTES == NFIELD_EXPECTED_ALIGN,
              "the package must pass on the Eigen alignment nfield was built with");

int main() {
  nfield::fields::FieldOptions options;
  options.input_dim = 2;
  options.hidden = {32, 32};
  options.first_omega = 5;
  const nfield::fields::Field<double> field(options);

  Eigen::MatrixXd x(3, 2);
  x << 0.1, 0.2, -0.4, 0.3, 0.7, -0.6;
  const nfield::autodiff::StreamLayout layout(nfield::autodiff::StreamSpec::laplacian(2));
  nfield::autodiff::Streams<double> out;
  field.evaluate(layout, x, out);

  const double h = 1e-4;
  double worst = 0;
  for (Eigen::Index n = 0; n < x.rows(); ++n) {
    double difference = -4 * field.values(x.row(n))(0, 0);
    for (int axis = 0; axis < 2; ++axis)
      for (double sign : {-1.0, 1.0}) {
        Eigen::MatrixXd y = x.row(n);
        y(0, axis) += sign * h;
        difference += field.values(y)(0, 0);
      }
    difference /= h * h;
    const double laplacian = out.stream(layout.op(0))(n, 0);
    worst = std::max(worst, std::abs(laplacian - difference) / (1 + std::abs(difference)));
    std::printf("u(%+.1f, %+.1f) = %+.6f  Δu = %+.6f (differences %+.6f)\n", x(n, 0), x(n, 1),
                out.stream(layout.value())(n, 0), laplacian, difference);
  }
  if (worst > 1e-4) {
    std::printf("consumer: Δu disagrees with differences (relative %.1e)\n", worst);
    return 1;
  }
  std::printf("consumer: ok (%ld parameters)\n", static_cast<long>(field.parameter_count()));
  return 0;
}
