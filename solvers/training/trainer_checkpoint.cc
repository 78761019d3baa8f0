// SPDX-License-Identifier: MIT
// The trainer's part of a checkpoint: where training is, the optimizer's and the strategies'
// state, the points of the current step, the engine and sequences (Trainer::save_state).
#include <sstream>
#include <stdexcept>

#include "io/hdf5_file.h"
#include "solvers/training/trainer.h"

namespace nfield::solvers {

template <typename Scalar>
void Trainer<Scalar>::save_state(io::H5Writer& file) const {
  file.create_group("trainer");
  file.write_attribute("trainer", "stage", static_cast<std::int64_t>(stage_));
  file.write_attribute("trainer", "stage_step", static_cast<std::int64_t>(stage_step_));
  file.write_attribute("trainer", "global_step", static_cast<std::int64_t>(global_step_));
  // Absent: one process (checkpoints of serial runs stay as they were).
  if (parallel())
    file.write_attribute("trainer", "mpi_ranks", static_cast<std::int64_t>(communicator_.size()));
  std::ostringstream engine;
  engine << rng_;
  file.write_attribute("trainer", "random_engine", engine.str());
  if (optimizer_) optimizer_->save(file, "trainer");
  for (size_t k = 0; k < terms_.size(); ++k)
    // Points with a context (rays and their pixels) are drawn anew on resume.
    if (terms_[k].points.x.size() > 0 && !terms_[k].points.context) {
      file.write("trainer/points/" + std::to_string(k), terms_[k].points.x);
      if (!terms_[k].points.groups.empty())
        file.write("trainer/groups/" + std::to_string(k),
                   std::vector<std::int64_t>(terms_[k].points.groups.begin(), terms_[k].points.groups.end()));
      if (terms_[k].points.tangents.size() > 0)
        file.write("trainer/tangents/" + std::to_string(k), terms_[k].points.tangents);
    }
  file.write("trainer/stage_losses", stage_losses_);
  std::vector<std::int64_t> iterations;
  for (size_t k = 0; k < stage_ends_.size(); ++k) {
    iterations.push_back(stage_ends_[k].iterations);
    const std::string key = "stage_end_" + std::to_string(k);
    file.write_attribute("trainer", key, stage_ends_[k].ended);
    file.write_attribute("trainer", key + "_termination", stage_ends_[k].termination);
    file.write_attribute("trainer", key + "_message", stage_ends_[k].message);
  }
  file.write("trainer/stage_iterations", iterations);
  if (watch_.retries > 0)
    file.write_attribute("trainer", "divergence_retries", static_cast<std::int64_t>(watch_.retries));
  file.write("trainer/stage_errors", stage_errors_);
  for (size_t k = 0; k < terms_.size(); ++k)
    if (terms_[k].sequence)
      file.write_attribute("trainer", "sequence_" + std::to_string(k), terms_[k].sequence->state());
  for (const auto& s : strategies_) s->save(file, "trainer");
  unknowns_.save(file);
}

template <typename Scalar>
void Trainer<Scalar>::load_state(const io::H5Reader& file) {
  const std::int64_t ranks = file.has_attribute("trainer", "mpi_ranks")
                                 ? file.read_attribute<std::int64_t>("trainer", "mpi_ranks")
                                 : 1;
  if (ranks != communicator_.size())
    throw std::runtime_error(
        file.path().string() + ": written by a run over " + std::to_string(ranks) + " MPI rank" +
        (ranks == 1 ? "" : "s") + ", resumed over " + std::to_string(communicator_.size()) +
        "; resume it with the same number (" +
        (ranks == 1 ? std::string("without mpirun, or mpirun -np 1")
                    : "mpirun -np " + std::to_string(ranks)) +
        "): how a step's sums split over ranks decides the bits of the run");
  stage_ = static_cast<int>(file.read_attribute<std::int64_t>("trainer", "stage"));
  stage_step_ = static_cast<int>(file.read_attribute<std::int64_t>("trainer", "stage_step"));
  global_step_ = file.read_attribute<std::int64_t>("trainer", "global_step");
  std::istringstream engine(file.read_attribute<std::string>("trainer", "random_engine"));
  engine >> rng_;
  optimizer_.reset();
  if (stage_ < static_cast<int>(options_.stages.size())) {
    optimizer_ = options_.stages[stage_].settings->clone();
    optimizer_->load(file, "trainer");
  }
  for (size_t k = 0; k < terms_.size(); ++k) {
    const std::string name = "trainer/points/" + std::to_string(k);
    if (!file.has_dataset(name)) continue;
    terms_[k].points = TermPoints(file.read_matrix<double>(name));
    const std::string groups = "trainer/groups/" + std::to_string(k);
    if (file.has_dataset(groups)) {
      const auto g = file.read_vector<std::int64_t>(groups);
      terms_[k].points.groups.assign(g.data(), g.data() + g.size());
    }
    const std::string tangents = "trainer/tangents/" + std::to_string(k);
    if (file.has_dataset(tangents)) terms_[k].points.tangents = file.read_matrix<double>(tangents);
    set_points(k);
  }
  if (file.has_dataset("trainer/stage_losses")) {
    const Eigen::VectorXd s = file.read_vector<double>("trainer/stage_losses");
    stage_losses_.assign(s.data(), s.data() + s.size());
  }
  // Checkpoints from before stage reports: their stages are taken as completed.
  stage_ends_.assign(stage_losses_.size(), StageEnd{});
  for (size_t k = 0; k < stage_ends_.size(); ++k) {
    stage_ends_[k].iterations = k < options_.stages.size() ? options_.stages[k].steps : 0;
    const std::string key = "stage_end_" + std::to_string(k);
    if (!file.has_attribute("trainer", key)) continue;
    stage_ends_[k].ended = file.read_attribute<std::string>("trainer", key);
    stage_ends_[k].termination = file.read_attribute<std::string>("trainer", key + "_termination");
    stage_ends_[k].message = file.read_attribute<std::string>("trainer", key + "_message");
  }
  if (file.has_dataset("trainer/stage_iterations")) {
    const auto it = file.read_vector<std::int64_t>("trainer/stage_iterations");
    for (Eigen::Index k = 0; k < it.size() && k < static_cast<Eigen::Index>(stage_ends_.size()); ++k)
      stage_ends_[k].iterations = static_cast<int>(it[k]);
  }
  watch_.retries = file.has_attribute("trainer", "divergence_retries")
                       ? static_cast<int>(file.read_attribute<std::int64_t>("trainer", "divergence_retries"))
                       : 0;
  if (file.has_dataset("trainer/stage_errors")) {
    const Eigen::VectorXd e = file.read_vector<double>("trainer/stage_errors");
    stage_errors_.assign(e.data(), e.data() + e.size());
  }
  // Wall times are not state (a resumed run must end bit-identical): unknown for stages run
  // before the resume.
  stage_seconds_.assign(stage_losses_.size(), std::numeric_limits<double>::quiet_NaN());
  for (size_t k = 0; k < terms_.size(); ++k) {
    const std::string name = "sequence_" + std::to_string(k);
    if (terms_[k].sequence && file.has_attribute("trainer", name))
      terms_[k].sequence->set_state(file.read_attribute<std::string>("trainer", name));
  }
  for (const auto& s : strategies_) s->load(file, "trainer");
  unknowns_.load(file);
}

template void Trainer<float>::save_state(io::H5Writer&) const;
template void Trainer<double>::save_state(io::H5Writer&) const;
template void Trainer<float>::load_state(const io::H5Reader&);
template void Trainer<double>::load_state(const io::H5Reader&);

}  // namespace nfield::solvers
