// SPDX-License-Identifier: MIT
#include "solvers/training/trained_unknowns.h"

#include <algorithm>

namespace nfield::solvers {

// About 500 samples of the trajectory over the run, whatever its length.
constexpr long kTrajectorySamples = 500;

template <typename Scalar>
TrainedUnknowns<Scalar>::TrainedUnknowns(std::shared_ptr<UnknownConstants> unknowns, fields::Field<Scalar>& field,
                                         long total_steps)
    : unknowns_(std::move(unknowns)), field_(field),
      every_(static_cast<int>(std::max(1L, total_steps / kTrajectorySamples))) {
  if (!active()) return;
  if (field_.extra_parameters() != unknowns_->count()) field_.set_extra_parameters(unknowns_->initial_raw());
  before_pass(field_.parameters().data());
}

template <typename Scalar>
void TrainedUnknowns<Scalar>::before_pass(const Scalar* theta) {
  if (!active()) return;
  unknowns_->set_raw(theta + field_.network_parameter_count());
  sink_.clear();
}

template <typename Scalar>
void TrainedUnknowns<Scalar>::add_gradient(Scalar* gradient) {
  if (!active()) return;
  const Eigen::VectorXd g = sink_.sum(unknowns_->count());
  Scalar* tail = gradient + field_.network_parameter_count();
  for (int i = 0; i < unknowns_->count(); ++i)
    tail[i] += static_cast<Scalar>(g(i) * unknowns_->raw_derivative(i));
  sink_.clear();
}

template <typename Scalar>
void TrainedUnknowns<Scalar>::after_step(long step) {
  if (!active()) return;
  unknowns_->set_raw(field_.parameters().data() + field_.network_parameter_count());
  if (step % every_ == 0 || step == 1) trajectory_.push_back({step, unknowns_->values()});
}

template <typename Scalar>
void TrainedUnknowns<Scalar>::progress(std::vector<std::pair<std::string, double>>& extras) const {
  if (!active()) return;
  for (int i = 0; i < unknowns_->count(); ++i) extras.emplace_back(unknowns_->items()[i].name, unknowns_->value(i));
}

template <typename Scalar>
void TrainedUnknowns<Scalar>::save(io::H5Writer& file) const {
  if (!active()) return;
  const Eigen::Index n = field_.network_parameter_count();
  file.write("trainer/unknowns/raw", field_.parameters().segment(n, unknowns_->count()).template cast<double>().eval());
  Eigen::MatrixXd samples(static_cast<Eigen::Index>(trajectory_.size()), 1 + unknowns_->count());
  for (std::size_t s = 0; s < trajectory_.size(); ++s) {
    samples(static_cast<Eigen::Index>(s), 0) = static_cast<double>(trajectory_[s].step);
    for (int i = 0; i < unknowns_->count(); ++i)
      samples(static_cast<Eigen::Index>(s), 1 + i) = trajectory_[s].values[static_cast<std::size_t>(i)];
  }
  if (samples.rows() > 0) file.write("trainer/unknowns/trajectory", samples);
}

template <typename Scalar>
void TrainedUnknowns<Scalar>::load(const io::H5Reader& file) {
  if (!active() || !file.has_dataset("trainer/unknowns/raw")) return;
  const Eigen::VectorXd raw = file.read_vector<double>("trainer/unknowns/raw");
  if (raw.size() != unknowns_->count())
    throw std::runtime_error(file.path().string() + ": the checkpoint has " + std::to_string(raw.size()) +
                             " unknown constants, the config " + std::to_string(unknowns_->count()));
  // Written from the training scalar: exact when read back in it.
  field_.parameters().tail(unknowns_->count()) = raw.cast<Scalar>();
  unknowns_->set_raw(field_.parameters().data() + field_.network_parameter_count());
  trajectory_.clear();
  if (!file.has_dataset("trainer/unknowns/trajectory")) return;
  const Eigen::MatrixXd samples = file.read_matrix<double>("trainer/unknowns/trajectory");
  for (Eigen::Index s = 0; s < samples.rows(); ++s) {
    UnknownSample sample{static_cast<long>(samples(s, 0)), {}};
    for (int i = 0; i < unknowns_->count(); ++i) sample.values.push_back(samples(s, 1 + i));
    trajectory_.push_back(std::move(sample));
  }
}

template class TrainedUnknowns<float>;
template class TrainedUnknowns<double>;

}  // namespace nfield::solvers
