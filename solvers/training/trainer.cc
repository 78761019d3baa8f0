// SPDX-License-Identifier: MIT
#include "solvers/training/trainer.h"

#include <chrono>
#include <cmath>
#include <algorithm>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "solvers/conditions/hard_constraints.h"

namespace nfield::solvers {
namespace {

double now_seconds() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

}  // namespace

template <typename Scalar>
Trainer<Scalar>::Trainer(const Problem& problem, fields::Field<Scalar>& field,
                         TrainingOptions options, Communicator* communicator)
    : problem_(problem), field_(field),
      communicator_(communicator ? *communicator : world_communicator()),
      options_(std::move(options)), rng_(options_.seed) {
  terms_ = with_ansatz(problem_.loss_terms(), problem_.ansatz());  // hard conditions: u = A + D·N
  for (const LossTerm& term : terms_) {
    names_.push_back(term.name);
    layouts_.emplace_back(term.spec);
    if (!options_.batch.count(term.batch_key))
      throw std::invalid_argument("training.batch has no entry '" + term.batch_key +
                                  "' for loss term '" + term.name + "'");
  }
  losses_.assign(terms_.size(), 0.0);
  balance_.assign(terms_.size(), 1.0);
  pde_ = problem_.residual_term();
  if ((options_.adaptive.enabled || options_.causal.enabled || options_.balance.method != "fixed") &&
      (pde_ < 0 || pde_ >= static_cast<int>(terms_.size())))
    throw std::invalid_argument("training.adaptive, balance and causal need a PDE residual term");
  if (options_.causal.enabled && !problem_.domain().has_time())
    throw std::invalid_argument("training.causal needs a time axis (domain.time)");
  if (options_.sampler != "uniform")
    for (size_t k = 0; k < terms_.size(); ++k)
      // Seeds apart from the engine's and from each other (UnitSequence mixes them further).
      sequences_.emplace_back(options_.sampler, options_.seed * 0x100000001B3ull + 7919 * (k + 1));
  points_.resize(terms_.size());
  points_scalar_.resize(terms_.size());
  tangents_scalar_.resize(terms_.size());
  residuals_.resize(terms_.size());
  field_.set_evaluation({options_.block, options_.threads});
}

template <typename Scalar>
Trainer<Scalar>::~Trainer() = default;

template <typename Scalar>
void Trainer<Scalar>::resample() {
  for (size_t k = 0; k < terms_.size(); ++k) {
    {
      const AttachSequence attach(rng_, sequences_.empty() ? nullptr : &sequences_[k]);
      points_[k] = terms_[k].sample(rng_, options_.batch.at(terms_[k].batch_key));
    }
    if (static_cast<int>(k) == pde_) previous_adaptive_rows_ = adaptive_points_.rows();
    if (static_cast<int>(k) == pde_ && adaptive_points_.rows() > 0) {
      if (!points_[k].groups.empty() || points_[k].tangents.size() > 0)
        throw std::logic_error("training.adaptive: loss term '" + terms_[k].name +
                               "' reads groups of points or per-point tangents; refinement adds "
                               "single points");
      Eigen::MatrixXd joined(points_[k].x.rows() + adaptive_points_.rows(), points_[k].x.cols());
      joined << points_[k].x, adaptive_points_;
      points_[k].x = std::move(joined);
    }
    points_scalar_[k] = points_[k].x.template cast<Scalar>();
    tangents_scalar_[k] = points_[k].tangents.template cast<Scalar>();
    residuals_[k] = terms_[k].residual(points_[k]);
  }
}

template <typename Scalar>
double Trainer<Scalar>::term_loss(size_t k, const Scalar* params, double weight, Scalar* gradient) {
  const bool causal = options_.causal.enabled && static_cast<int>(k) == pde_ &&
                      causal_.point_weights.size() == points_[k].x.rows();
  const TermPoints& points = points_[k];
  const Eigen::VectorXd* point_weights = causal ? &causal_.point_weights : nullptr;
  const bool tangents = tangents_scalar_[k].size() > 0;
  if (!parallel()) {
    const ResidualLoss<Scalar> loss(*residuals_[k], weight, points.residual_rows(), point_weights);
    const autodiff::Batch<Scalar> batch{points_scalar_[k],
                                        tangents ? &tangents_scalar_[k] : nullptr, points.groups};
    return field_.value_and_gradient(params, layouts_[k], batch, loss, gradient);
  }
  // This rank's residual rows, and the points they read: rows [first, first + count) of x.
  const Share share = share_of(points.residual_rows(), communicator_.rank(), communicator_.size());
  if (share.count == 0) return 0;
  Eigen::Index first = share.first, count = share.count;
  std::vector<Eigen::Index> groups;
  if (!points.groups.empty()) {
    first = points.groups[share.first];
    count = points.groups[share.first + share.count] - first;
    groups.assign(points.groups.begin() + share.first,
                  points.groups.begin() + share.first + share.count + 1);
    for (Eigen::Index& g : groups) g -= first;
  }
  const ResidualLoss<Scalar> loss(*residuals_[k], weight, points.residual_rows(), point_weights,
                                  first);
  autodiff::Matrix<Scalar> share_tangents;
  if (tangents) share_tangents = tangents_scalar_[k].middleRows(first, count);
  const autodiff::Batch<Scalar> batch{points_scalar_[k].middleRows(first, count),
                                      tangents ? &share_tangents : nullptr, groups};
  return field_.value_and_gradient(params, layouts_[k], batch, loss, gradient);
}

template <typename Scalar>
void Trainer<Scalar>::sum_over_ranks(Scalar* gradient) {
  if (!parallel()) return;
  communicator_.allreduce_sum(gradient, static_cast<std::size_t>(field_.parameter_count()));
  communicator_.allreduce_sum(losses_.data(), losses_.size());
}

template <typename Scalar>
double Trainer<Scalar>::loss_and_gradient_at(const Scalar* params, Scalar* gradient) {
  if (std::any_of(residuals_.begin(), residuals_.end(), [](const auto& r) { return r == nullptr; }))
    resample();
  return loss_and_gradient(params, gradient);
}

template <typename Scalar>
double Trainer<Scalar>::loss_and_gradient(const Scalar* params, Scalar* gradient) {
  Eigen::Map<autodiff::Vector<Scalar>>(gradient, field_.parameter_count()).setZero();
  for (size_t k = 0; k < terms_.size(); ++k)
    losses_[k] = term_loss(k, params, terms_[k].weight * balance_[k], gradient);
  sum_over_ranks(gradient);
  double total = 0;
  for (double loss : losses_) total += loss;
  return total;
}

template <typename Scalar>
void Trainer<Scalar>::balanced_gradient(Scalar* gradient) {
  const Eigen::Index n = field_.parameter_count();
  std::vector<autodiff::Vector<Scalar>> g(terms_.size());
  for (size_t k = 0; k < terms_.size(); ++k) {
    g[k] = autodiff::Vector<Scalar>::Zero(n);
    losses_[k] = term_loss(k, field_.parameters().data(), terms_[k].weight, g[k].data());
    if (parallel()) communicator_.allreduce_sum(g[k].data(), static_cast<std::size_t>(n));
  }
  if (parallel()) communicator_.allreduce_sum(losses_.data(), losses_.size());
  const Eigen::VectorXd pde = g[pde_].template cast<double>();
  const double alpha = options_.balance.alpha;
  Eigen::Map<autodiff::Vector<Scalar>> sum(gradient, n);
  sum.setZero();
  for (size_t k = 0; k < terms_.size(); ++k) {
    if (static_cast<int>(k) != pde_) {
      const double target = grad_norm_target(pde, g[k].template cast<double>(), terms_[k].weight, balance_[k]);
      balance_[k] = (1 - alpha) * balance_[k] + alpha * target;
    }
    sum += static_cast<Scalar>(balance_[k]) * g[k];
    losses_[k] *= balance_[k];
  }
}

template <typename Scalar>
Eigen::VectorXd Trainer<Scalar>::squared_residuals(size_t k, const Eigen::MatrixXd& x,
                                                   const Residual& residual) const {
  autodiff::Streams<Scalar> out;
  field_.evaluate(layouts_[k], x.cast<Scalar>(), out);
  autodiff::Streams<double> out_d;
  out_d.points = out.points;
  out_d.count = out.count;
  out_d.data = out.data.template cast<double>();
  Eigen::MatrixXd r;
  residual.evaluate(0, layouts_[k], out_d, r);
  return r.rowwise().squaredNorm();
}

template <typename Scalar>
void Trainer<Scalar>::begin_stage() {
  field_.begin_stage(stage_);
  for (size_t k = 0; k < terms_.size(); ++k) {
    if (!terms_[k].begin_stage) continue;
    terms_[k].begin_stage(stage_);
    if (residuals_[k]) residuals_[k] = terms_[k].residual(points_[k]);
  }
}

template <typename Scalar>
int Trainer<Scalar>::segment_length(int resample_every, bool with_causal) const {
  int segment = options_.stages[stage_].steps;
  if (resample_every > 0) segment = std::min(segment, resample_every);
  if (with_causal && options_.causal.enabled) segment = std::min(segment, options_.causal.every);
  if (options_.adaptive.enabled) segment = std::min(segment, options_.adaptive.every);
  return segment;
}

template <typename Scalar>
bool Trainer<Scalar>::ends_after_segment(int segment, int segment_start, bool early) const {
  const int steps = options_.stages[stage_].steps;
  return stage_step_ >= steps || (early && (segment >= steps || stage_step_ == segment_start));
}

template <typename Scalar>
void Trainer<Scalar>::renew_points(int resample_every) {
  if (options_.adaptive.enabled) refine();
  if (resample_every > 0)
    resample();
  else if (options_.adaptive.enabled)
    join_adaptive_points();
}

template <typename Scalar>
void Trainer<Scalar>::join_adaptive_points() {
  // The stage's own points stay; only the extra set behind them changes.
  const Eigen::Index own = points_[pde_].x.rows() - previous_adaptive_rows_;
  Eigen::MatrixXd joined(own + adaptive_points_.rows(), points_[pde_].x.cols());
  joined << points_[pde_].x.topRows(own), adaptive_points_;
  points_[pde_].x = std::move(joined);
  points_scalar_[pde_] = points_[pde_].x.template cast<Scalar>();
  residuals_[pde_] = terms_[pde_].residual(points_[pde_]);
  previous_adaptive_rows_ = adaptive_points_.rows();
}

template <typename Scalar>
void Trainer<Scalar>::refine() {
  TermPoints candidates;
  {
    const AttachSequence attach(rng_, sequences_.empty() ? nullptr : &sequences_[pde_]);
    candidates = terms_[pde_].sample(rng_, options_.adaptive.candidates);
  }
  const auto residual = terms_[pde_].residual(candidates);
  const std::vector<Eigen::Index> best =
      largest(squared_residuals(pde_, candidates.x, *residual), options_.adaptive.add);
  append_capped(adaptive_points_, candidates.x(best, Eigen::all), options_.adaptive.max_points);
}

template <typename Scalar>
void Trainer<Scalar>::update_causal() {
  const Eigen::VectorXd r2 = squared_residuals(pde_, points_[pde_].x, *residuals_[pde_]);
  const auto [t0, t1] = problem_.domain().time();
  causal_ = solvers::causal_weights(points_[pde_].x.col(problem_.domain().time_column()), r2, t0, t1,
                                    options_.causal.slices, options_.causal.epsilon);
}

template <typename Scalar>
std::vector<std::pair<std::string, double>> Trainer<Scalar>::extra_metrics() const {
  std::vector<std::pair<std::string, double>> out;
  if (options_.causal.enabled && !causal_.weights.empty())
    out.emplace_back("causal_min_weight", causal_.min_weight());
  if (options_.balance.method != "fixed")
    for (size_t k = 0; k < terms_.size(); ++k) out.emplace_back("balance_weight_" + names_[k], balance_[k]);
  if (options_.adaptive.enabled)
    out.emplace_back("adaptive_points", static_cast<double>(adaptive_points_.rows()));
  return out;
}

template <typename Scalar>
Progress Trainer<Scalar>::progress(double lr) const {
  const StageOptions& stage = options_.stages[stage_];
  Progress p;
  p.stage = stage_;
  p.optimizer = stage.optimizer;
  p.step = global_step_;
  p.total_steps = options_.total_steps();
  p.learning_rate = lr;
  p.term_names = names_;
  p.term_losses = losses_;
  for (double l : losses_) p.loss += l;
  if (options_.causal.enabled && !causal_.weights.empty())
    p.extras.emplace_back("causal min w", causal_.min_weight());
  const double elapsed = now_seconds() - stage_started_;
  const long done = global_step_ - stage_started_step_;
  p.steps_per_second = elapsed > 0 ? done / elapsed : 0;
  p.eta_seconds = p.steps_per_second > 0 ? (p.total_steps - p.step) / p.steps_per_second : 0;
  if (time_budget_ > 0) {
    // A time budget ends the stage first when it is shorter than its steps would take.
    const double left = std::max(0.0, time_budget_ - elapsed);
    const double later = p.steps_per_second > 0
                             ? (p.total_steps - (p.step - stage_step_ + stage.steps)) / p.steps_per_second
                             : 0;
    p.eta_seconds = std::min(p.eta_seconds, left + std::max(0.0, later));
  }
  return p;
}

template <typename Scalar>
void Trainer<Scalar>::prepare_step() {
  const bool refine_now = options_.adaptive.enabled && global_step_ > 0 &&
                          global_step_ % options_.adaptive.every == 0;
  if (refine_now) refine();
  const bool drawn = std::all_of(residuals_.begin(), residuals_.end(), [](const auto& r) { return r != nullptr; });
  if (refine_now || global_step_ % options_.resample_every == 0 || !drawn) resample();
  if (options_.causal.enabled) update_causal();
}

template <typename Scalar>
void Trainer<Scalar>::finish_step(double learning_rate, double milliseconds) {
  step_ms_.push_back(milliseconds);
  ++stage_step_;
  ++global_step_;
  if (callbacks_->progress) callbacks_->progress(progress(learning_rate));
  if (options_.checkpoint_every > 0 && global_step_ % options_.checkpoint_every == 0 &&
      callbacks_->checkpoint)
    callbacks_->checkpoint();
}

template <typename Scalar>
bool Trainer<Scalar>::run(const Callbacks& callbacks) {
  // Every rank built or loaded the same parameters; rank 0's make sure of it.
  if (parallel())
    communicator_.broadcast(field_.parameters().data(),
                            static_cast<std::size_t>(field_.parameter_count()));
  for (; stage_ < static_cast<int>(options_.stages.size()); ++stage_) {
    const StageOptions& stage = options_.stages[stage_];
    const double stage_started = stage_started_ = now_seconds();
    stage_started_step_ = global_step_;
    begin_stage();
    time_budget_ = 0;
    if (callbacks.stage_begins) callbacks.stage_begins(progress(0.0));
    if (!optimizer_) optimizer_ = stage.settings->clone();  // a resumed stage has its own
    callbacks_ = &callbacks;
    TrainingStage<Scalar> view(*this);
    if (!optimizer_->run(view)) return false;
    double total = 0;
    for (double l : losses_) total += l;
    stage_losses_.push_back(total);
    stage_seconds_.push_back(now_seconds() - stage_started);
    stage_errors_.push_back(callbacks.stage_error ? callbacks.stage_error()
                                                  : std::numeric_limits<double>::quiet_NaN());
    stage_step_ = 0;
    optimizer_.reset();
  }
  return true;
}

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
    if (points_[k].x.size() > 0 && !points_[k].context) {
      file.write("trainer/points/" + std::to_string(k), points_[k].x);
      if (!points_[k].groups.empty())
        file.write("trainer/groups/" + std::to_string(k),
                   std::vector<std::int64_t>(points_[k].groups.begin(), points_[k].groups.end()));
      if (points_[k].tangents.size() > 0)
        file.write("trainer/tangents/" + std::to_string(k), points_[k].tangents);
    }
  file.write("trainer/stage_losses", stage_losses_);
  file.write("trainer/stage_errors", stage_errors_);
  for (size_t k = 0; k < sequences_.size(); ++k)
    file.write_attribute("trainer", "sequence_" + std::to_string(k), sequences_[k].state());
  if (adaptive_points_.rows() > 0) file.write("trainer/adaptive_points", adaptive_points_);
  file.write("trainer/balance_weights", balance_);
  if (!causal_.weights.empty()) file.write("trainer/causal_weights", causal_.weights);
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
    points_[k] = TermPoints(file.read_matrix<double>(name));
    const std::string groups = "trainer/groups/" + std::to_string(k);
    if (file.has_dataset(groups)) {
      const auto g = file.read_vector<std::int64_t>(groups);
      points_[k].groups.assign(g.data(), g.data() + g.size());
    }
    const std::string tangents = "trainer/tangents/" + std::to_string(k);
    if (file.has_dataset(tangents)) points_[k].tangents = file.read_matrix<double>(tangents);
    points_scalar_[k] = points_[k].x.template cast<Scalar>();
    tangents_scalar_[k] = points_[k].tangents.template cast<Scalar>();
    residuals_[k] = terms_[k].residual(points_[k]);
  }
  if (file.has_dataset("trainer/stage_losses")) {
    const Eigen::VectorXd s = file.read_vector<double>("trainer/stage_losses");
    stage_losses_.assign(s.data(), s.data() + s.size());
  }
  if (file.has_dataset("trainer/stage_errors")) {
    const Eigen::VectorXd e = file.read_vector<double>("trainer/stage_errors");
    stage_errors_.assign(e.data(), e.data() + e.size());
  }
  // Wall times are not state (a resumed run must end bit-identical): unknown for stages run
  // before the resume.
  stage_seconds_.assign(stage_losses_.size(), std::numeric_limits<double>::quiet_NaN());
  for (size_t k = 0; k < sequences_.size(); ++k) {
    const std::string name = "sequence_" + std::to_string(k);
    if (file.has_attribute("trainer", name))
      sequences_[k].set_state(file.read_attribute<std::string>("trainer", name));
  }
  adaptive_points_.resize(0, 0);
  if (file.has_dataset("trainer/adaptive_points"))
    adaptive_points_ = file.read_matrix<double>("trainer/adaptive_points");
  if (file.has_dataset("trainer/balance_weights")) {
    const Eigen::VectorXd b = file.read_vector<double>("trainer/balance_weights");
    if (b.size() == static_cast<Eigen::Index>(balance_.size())) balance_.assign(b.data(), b.data() + b.size());
  }
  if (file.has_dataset("trainer/causal_weights")) {
    const Eigen::VectorXd c = file.read_vector<double>("trainer/causal_weights");
    causal_.weights.assign(c.data(), c.data() + c.size());
  }
}

template <typename Scalar>
int TrainingStage<Scalar>::index() const { return trainer_.stage_; }
template <typename Scalar>
int TrainingStage<Scalar>::steps() const { return trainer_.options_.stages[trainer_.stage_].steps; }
template <typename Scalar>
int TrainingStage<Scalar>::step() const { return trainer_.stage_step_; }
template <typename Scalar>
fields::Field<Scalar>& TrainingStage<Scalar>::field() { return trainer_.field_; }
template <typename Scalar>
std::size_t TrainingStage<Scalar>::term_count() const { return trainer_.terms_.size(); }
template <typename Scalar>
const std::string& TrainingStage<Scalar>::term_name(std::size_t k) const { return trainer_.names_.at(k); }
template <typename Scalar>
const TermPoints& TrainingStage<Scalar>::points(std::size_t k) const { return trainer_.points_.at(k); }
template <typename Scalar>
const autodiff::Matrix<Scalar>& TrainingStage<Scalar>::points_in_scalar(std::size_t k) const {
  return trainer_.points_scalar_.at(k);
}
template <typename Scalar>
const Residual& TrainingStage<Scalar>::residual(std::size_t k) const { return *trainer_.residuals_.at(k); }
template <typename Scalar>
const autodiff::StreamLayout& TrainingStage<Scalar>::layout(std::size_t k) const {
  return trainer_.layouts_.at(k);
}
template <typename Scalar>
double TrainingStage<Scalar>::weight(std::size_t k) const {
  return trainer_.terms_.at(k).weight * trainer_.balance_.at(k);
}
template <typename Scalar>
void TrainingStage<Scalar>::set_term_loss(std::size_t k, double loss) { trainer_.losses_.at(k) = loss; }
template <typename Scalar>
double TrainingStage<Scalar>::loss_and_gradient(const Scalar* params, Scalar* gradient) {
  return trainer_.loss_and_gradient(params, gradient);
}
template <typename Scalar>
void TrainingStage<Scalar>::prepare_step() { trainer_.prepare_step(); }
template <typename Scalar>
void TrainingStage<Scalar>::step_gradient(Scalar* gradient) {
  const TrainingOptions& o = trainer_.options_;
  if (o.balance.method == "grad_norm" && trainer_.global_step_ % o.balance.every == 0)
    trainer_.balanced_gradient(gradient);
  else
    trainer_.loss_and_gradient(trainer_.field_.parameters().data(), gradient);
}
template <typename Scalar>
void TrainingStage<Scalar>::draw_points() { trainer_.resample(); }
template <typename Scalar>
bool TrainingStage<Scalar>::causal() const { return trainer_.options_.causal.enabled; }
template <typename Scalar>
void TrainingStage<Scalar>::update_causal_weights() { trainer_.update_causal(); }
template <typename Scalar>
int TrainingStage<Scalar>::segment_length(int resample_every, bool with_causal) const {
  return trainer_.segment_length(resample_every, with_causal);
}
template <typename Scalar>
bool TrainingStage<Scalar>::ends_after_segment(int segment, int segment_start, bool early) const {
  return trainer_.ends_after_segment(segment, segment_start, early);
}
template <typename Scalar>
void TrainingStage<Scalar>::renew_points(int resample_every) { trainer_.renew_points(resample_every); }
template <typename Scalar>
double TrainingStage<Scalar>::seconds() const {
  double seconds = now_seconds() - trainer_.stage_started_;
  // Rank 0's clock for all: a learning rate or the end of a time budget must not differ.
  if (trainer_.parallel()) trainer_.communicator_.broadcast(&seconds, 1);
  return seconds;
}
template <typename Scalar>
Communicator& TrainingStage<Scalar>::communicator() const { return trainer_.communicator_; }
template <typename Scalar>
void TrainingStage<Scalar>::set_time_budget(double seconds) { trainer_.time_budget_ = seconds; }
template <typename Scalar>
bool TrainingStage<Scalar>::stop_requested() const {
  const auto& stop = trainer_.callbacks_->stop_requested;
  const bool requested = stop && stop();
  // One rank's request stops them all, at the same step.
  return trainer_.parallel() ? trainer_.communicator_.any(requested) : requested;
}
template <typename Scalar>
void TrainingStage<Scalar>::finish_step(double learning_rate, double milliseconds) {
  trainer_.finish_step(learning_rate, milliseconds);
}
template <typename Scalar>
void TrainingStage<Scalar>::finish_early() {
  const int steps = this->steps();
  trainer_.global_step_ += steps - trainer_.stage_step_;
  trainer_.stage_step_ = steps;
}

template class TrainingStage<float>;
template class TrainingStage<double>;
template class Trainer<float>;
template class Trainer<double>;

}  // namespace nfield::solvers
