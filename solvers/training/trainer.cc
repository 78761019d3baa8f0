// SPDX-License-Identifier: MIT
#include "solvers/training/trainer.h"

#include <chrono>
#include <cmath>
#include <algorithm>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "solvers/core/ansatz.h"
#include "solvers/training/block_allocation.h"

namespace nfield::solvers {
namespace {

double now_seconds() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

// This rank's share of a term's residual rows (points, or groups of points), and the points
// it reads: rows [first, first + count) of x, with the share's group offsets from `first`.
struct RankRows {
  Eigen::Index residual_rows = 0;
  Eigen::Index first = 0, count = 0;
  std::vector<Eigen::Index> groups;  // empty: the term has no groups
};

RankRows rank_rows(const TermPoints& points, const Communicator& communicator) {
  const Share share = share_of(points.residual_rows(), communicator.rank(), communicator.size());
  RankRows rows{share.count, share.first, share.count, {}};
  if (points.groups.empty() || share.count == 0) return rows;
  rows.first = points.groups[share.first];
  rows.count = points.groups[share.first + share.count] - rows.first;
  rows.groups.assign(points.groups.begin() + share.first, points.groups.begin() + share.first + share.count + 1);
  for (Eigen::Index& g : rows.groups) g -= rows.first;
  return rows;
}

}  // namespace

std::string Divergence::describe() const {
  std::ostringstream out;
  out << "step " << step << " (stage " << stage + 1 << ", " << optimizer << "): " << what
      << " is not finite; ";
  if (last_finite_step > 0) out << "last finite loss " << last_finite_loss << " at step " << last_finite_step;
  else out << "no step of this run had a finite loss";
  return out.str();
}

template <typename Scalar>
class Trainer<Scalar>::View final : public StrategyView<Scalar> {
 public:
  explicit View(Trainer& trainer) : t_(trainer) {}

  long step() const override { return t_.global_step_; }
  double term_weight(std::size_t k) const override { return t_.terms_.at(k).term.weight; }
  const TermPoints& points(std::size_t k) const override { return t_.terms_.at(k).points; }
  Eigen::Index parameter_count() const override { return t_.field_.parameter_count(); }
  Communicator& communicator() const override { return t_.communicator_; }
  TermPoints sample(std::size_t k, Eigen::Index n) override { return t_.sample(k, n); }
  Eigen::VectorXd squared_residuals(std::size_t k) const override {
    return t_.squared_residuals(k, t_.terms_.at(k).points.x, *t_.terms_.at(k).residual);
  }
  Eigen::VectorXd squared_residuals(std::size_t k, const TermPoints& points) const override {
    return t_.squared_residuals(k, points.x, *t_.terms_.at(k).term.residual(points));
  }
  void replace_points(std::size_t k, Eigen::MatrixXd x) override {
    t_.terms_.at(k).points.x = std::move(x);
    t_.set_points(k);
  }
  double term_loss(std::size_t k, double weight, Scalar* gradient) override {
    return t_.term_loss(k, t_.field_.parameters().data(), weight, gradient);
  }
  void set_term_loss(std::size_t k, double loss) override { t_.losses_.at(k) = loss; }
  const fields::Field<Scalar>* field() const override { return &t_.field_; }

 private:
  Trainer& t_;
};

template <typename Scalar>
Trainer<Scalar>::Trainer(const Problem& problem, fields::Field<Scalar>& field,
                         TrainingOptions options, Communicator* communicator)
    : problem_(problem), field_(field),
      communicator_(communicator ? *communicator : world_communicator()),
      options_(std::move(options)), rng_(options_.seed),
      unknowns_(problem.unknowns(), field, options_.total_steps()) {
  for (LossTerm& term : with_ansatz(problem_.loss_terms(), problem_.ansatz())) {  // u = A + D·N
    if (!term.batch_key.empty() && !options_.batch.count(term.batch_key))
      throw std::invalid_argument("training.batch has no entry '" + term.batch_key +
                                  "' for loss term '" + term.name + "'");
    names_.push_back(term.name);
    autodiff::StreamLayout layout(term.spec);
    TermState state{std::move(term), std::move(layout)};
    // Seeds apart from the engine's and from each other (UnitSequence mixes them further).
    if (options_.sampler != "uniform")
      state.sequence.emplace(options_.sampler, options_.seed * 0x100000001B3ull + 7919 * (terms_.size() + 1));
    terms_.push_back(std::move(state));
  }
  losses_.assign(terms_.size(), 0.0);
  strategies_ = make_training_strategies<Scalar>(options_, problem_, names_);
  // A field with a block tree (field.type: acorn) reallocates its blocks and samples them.
  if (auto blocks = make_block_allocation(field_, options_.seed, terms_.size())) strategies_.push_back(std::move(blocks));
  field_.set_evaluation({options_.block, options_.threads});
}

template <typename Scalar>
Trainer<Scalar>::~Trainer() = default;

template <typename Scalar>
TermPoints Trainer<Scalar>::sample(size_t k, Eigen::Index n) {
  const AttachSequence attach(rng_, terms_[k].sequence ? &*terms_[k].sequence : nullptr);
  return terms_[k].term.sample(rng_, n);
}

template <typename Scalar>
void Trainer<Scalar>::set_points(size_t k) {
  terms_[k].x = terms_[k].points.x.template cast<Scalar>();
  terms_[k].tangents = terms_[k].points.tangents.template cast<Scalar>();
  terms_[k].residual = terms_[k].term.residual(terms_[k].points);
}

template <typename Scalar>
void Trainer<Scalar>::resample() {
  if (callbacks_ && callbacks_->before_draw) callbacks_->before_draw(global_step_, rng_);
  const long scale = stage_ < static_cast<int>(options_.stages.size()) ? options_.stages[stage_].batch_scale : 1;
  for (size_t k = 0; k < terms_.size(); ++k) {
    // A term with no batch key draws its own set (measurements: all of them, every step).
    terms_[k].points =
        sample(k, terms_[k].term.batch_key.empty() ? 0 : scale * options_.batch.at(terms_[k].term.batch_key));
    for (const auto& s : strategies_) s->points_drawn(k, terms_[k].points);
    set_points(k);
  }
}

template <typename Scalar>
double Trainer<Scalar>::loss_scale(size_t k) const {
  double scale = 1;
  for (const auto& s : strategies_) scale *= s->loss_scale(k);
  return scale;
}

template <typename Scalar>
double Trainer<Scalar>::term_loss(size_t k, const Scalar* params, double weight, Scalar* gradient) {
  const TermPoints& points = terms_[k].points;
  const Eigen::VectorXd* point_weights = nullptr;
  for (const auto& s : strategies_)
    if ((point_weights = s->point_weights(k, points))) break;
  const bool tangents = terms_[k].tangents.size() > 0;
  // Unknown constants (trained_unknowns.h): read at params' tail, their gradient added to it.
  unknowns_.before_pass(params);
  const auto with_unknowns = [&](double loss) {
    if (gradient) unknowns_.add_gradient(gradient);
    return loss;
  };
  if (!parallel()) {
    const ResidualLoss<Scalar> loss(*terms_[k].residual, weight, points.residual_rows(), point_weights, 0,
                                    unknowns_.gradient_sink());
    const autodiff::Batch<Scalar> batch{terms_[k].x,
                                        tangents ? &terms_[k].tangents : nullptr, points.groups};
    return with_unknowns(field_.value_and_gradient(params, terms_[k].layout, batch, loss, gradient));
  }
  const RankRows rows = rank_rows(points, communicator_);
  if (rows.residual_rows == 0) return 0;
  const Eigen::Index first = rows.first, count = rows.count;
  const ResidualLoss<Scalar> loss(*terms_[k].residual, weight, points.residual_rows(), point_weights,
                                  first, unknowns_.gradient_sink());
  autodiff::Matrix<Scalar> share_tangents;
  if (tangents) share_tangents = terms_[k].tangents.middleRows(first, count);
  const autodiff::Batch<Scalar> batch{terms_[k].x.middleRows(first, count),
                                      tangents ? &share_tangents : nullptr, rows.groups};
  return with_unknowns(field_.value_and_gradient(params, terms_[k].layout, batch, loss, gradient));
}

template <typename Scalar>
void Trainer<Scalar>::sum_over_ranks(Scalar* gradient) {
  if (!parallel()) return;
  communicator_.allreduce_sum(gradient, static_cast<std::size_t>(field_.parameter_count()));
  communicator_.allreduce_sum(losses_.data(), losses_.size());
}

template <typename Scalar>
double Trainer<Scalar>::loss_and_gradient_at(const Scalar* params, Scalar* gradient) {
  if (!drawn())
    resample();
  return loss_and_gradient(params, gradient);
}

template <typename Scalar>
double Trainer<Scalar>::loss_and_gradient(const Scalar* params, Scalar* gradient) {
  Eigen::Map<autodiff::Vector<Scalar>>(gradient, field_.parameter_count()).setZero();
  for (size_t k = 0; k < terms_.size(); ++k)
    losses_[k] = term_loss(k, params, terms_[k].term.weight * loss_scale(k), gradient);
  sum_over_ranks(gradient);
  double total = 0;
  for (double loss : losses_) total += loss;
  return total;
}

template <typename Scalar>
Eigen::VectorXd Trainer<Scalar>::squared_residuals(size_t k, const Eigen::MatrixXd& x,
                                                   const Residual& residual) const {
  autodiff::Streams<Scalar> out;
  field_.evaluate(terms_[k].layout, x.cast<Scalar>(), out);
  autodiff::Streams<double> out_d;
  out_d.points = out.points;
  out_d.count = out.count;
  out_d.data = out.data.template cast<double>();
  Eigen::MatrixXd r;
  residual.evaluate(0, terms_[k].layout, out_d, r);
  return r.rowwise().squaredNorm();
}

template <typename Scalar>
void Trainer<Scalar>::begin_stage() {
  field_.begin_stage(stage_);
  for (size_t k = 0; k < terms_.size(); ++k) {
    if (!terms_[k].term.begin_stage) continue;
    terms_[k].term.begin_stage(stage_);
    if (terms_[k].residual) terms_[k].residual = terms_[k].term.residual(terms_[k].points);
  }
}

template <typename Scalar>
int Trainer<Scalar>::segment_length(int resample_every, bool reweighted) const {
  int segment = options_.stages[stage_].steps;
  if (resample_every > 0) segment = std::min(segment, resample_every);
  for (const auto& s : strategies_) segment = std::min(segment, s->segment_limit(reweighted));
  return segment;
}

template <typename Scalar>
bool Trainer<Scalar>::ends_after_segment(int segment, int segment_start, bool early) const {
  const int steps = options_.stages[stage_].steps;
  return stage_step_ >= steps || (early && (segment >= steps || stage_step_ == segment_start));
}

template <typename Scalar>
void Trainer<Scalar>::renew_points(int resample_every) {
  View view(*this);
  for (const auto& s : strategies_) s->between_segments(view, resample_every > 0);
  if (resample_every > 0) resample();
}

template <typename Scalar>
void Trainer<Scalar>::update_weights() {
  View view(*this);
  for (const auto& s : strategies_) s->update_weights(view);
}

template <typename Scalar>
std::vector<std::pair<std::string, double>> Trainer<Scalar>::extra_metrics() const {
  std::vector<std::pair<std::string, double>> out;
  for (const auto& s : strategies_) s->metrics(out);
  return out;
}

template <typename Scalar>
std::vector<double> Trainer<Scalar>::balance_weights() const {
  std::vector<double> lambda(terms_.size());
  for (size_t k = 0; k < terms_.size(); ++k) lambda[k] = loss_scale(k);
  return lambda;
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
  for (const auto& s : strategies_) s->progress(p.extras);
  unknowns_.progress(p.extras);
  const double elapsed = now_seconds() - stage_started_;
  const long done = global_step_ - stage_started_step_;
  p.steps_per_second = elapsed > 0 ? done / elapsed : 0;
  p.eta_seconds = p.steps_per_second > 0 ? (stage.steps - stage_step_) / p.steps_per_second : 0;
  // A time budget ends the stage first when it is shorter than its steps would take.
  if (time_budget_ > 0) p.eta_seconds = std::min(p.eta_seconds, std::max(0.0, time_budget_ - elapsed));
  p.later_stages = static_cast<int>(options_.stages.size()) - 1 - stage_;
  for (const TermState& t : terms_) {
    const TermPoints& points = t.points;
    p.term_points.push_back(points.x.rows());
    p.term_groups.push_back(points.groups.empty() ? 0 : static_cast<Eigen::Index>(points.groups.size()) - 1);
  }
  return p;
}

template <typename Scalar>
void Trainer<Scalar>::prepare_step() {
  View view(*this);
  bool redraw = false;
  for (const auto& s : strategies_) redraw = s->before_step(view) || redraw;
  if (redraw || global_step_ % options_.resample_every == 0 || !drawn()) resample();
  update_weights();
}

template <typename Scalar>
void Trainer<Scalar>::step_gradient(Scalar* gradient) {
  View view(*this);
  for (const auto& s : strategies_)
    if (s->step_gradient(view, gradient)) return;
  loss_and_gradient(field_.parameters().data(), gradient);
}

template <typename Scalar>
void Trainer<Scalar>::record_divergence(std::string what) {
  Divergence d;
  d.step = global_step_ + 1;
  d.stage = stage_;
  d.optimizer = options_.stages[stage_].optimizer;
  d.what = std::move(what);
  d.last_finite_step = watch_.last_finite_step;
  if (!watch_.last_finite_losses.empty()) {
    d.last_finite_loss = 0;
    for (double l : watch_.last_finite_losses) d.last_finite_loss += l;  // in the order metrics.json sums
  }
  watch_.divergence = std::move(d);
}

template <typename Scalar>
bool Trainer<Scalar>::check_finite(const Scalar* gradient) {
  for (size_t k = 0; k < losses_.size(); ++k)
    if (!std::isfinite(losses_[k])) {
      record_divergence("loss term '" + names_[k] + "'");
      return false;
    }
  if (gradient && !Eigen::Map<const autodiff::Vector<Scalar>>(gradient, field_.parameter_count()).allFinite()) {
    record_divergence("the gradient");
    return false;
  }
  return true;
}

template <typename Scalar>
bool Trainer<Scalar>::check_finite_parameters() {
  if (field_.parameters().allFinite()) return true;
  record_divergence("the parameters after the update");
  return false;
}

template <typename Scalar>
bool Trainer<Scalar>::retry_after_divergence() {
  if (!watch_.divergence) return false;
  if (options_.on_divergence != "restore_and_halve_lr" || watch_.retries >= options_.divergence_retries)
    return false;
  ++watch_.retries;
  notice(watch_.divergence->describe() + "; back to step " + std::to_string(watch_.divergence->last_finite_step) +
         "'s parameters with the learning rate halved (retry " + std::to_string(watch_.retries) +
         " of " + std::to_string(options_.divergence_retries) + ")");
  watch_.divergence.reset();
  return true;
}

template <typename Scalar>
void Trainer<Scalar>::notice(const std::string& line) const {
  if (callbacks_ && callbacks_->notice) callbacks_->notice(line);
}

template <typename Scalar>
void Trainer<Scalar>::finish_step(double learning_rate, double milliseconds) {
  step_ms_.push_back(milliseconds);
  ++stage_step_;
  ++global_step_;
  double total = 0;
  for (double l : losses_) total += l;
  if (std::isfinite(total)) {
    watch_.last_finite_step = global_step_;
    watch_.last_finite_losses = losses_;
  }
  unknowns_.after_step(global_step_);
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
    stage_end_ = StageEnd{};
    TrainingStage<Scalar> view(*this);
    if (!optimizer_->run(view)) {
      if (watch_.divergence) {
        notice(watch_.divergence->describe() + "; the field is kept at the last parameters whose loss was finite");
        // The losses reported are those of the parameters kept.
        if (!watch_.last_finite_losses.empty()) losses_ = watch_.last_finite_losses;
      }
      return false;
    }
    stage_end_.iterations = stage_step_;
    if (stage_end_.ended != "completed") {
      std::string line = "stage " + std::to_string(stage_ + 1) + " (" + stage.optimizer + ") ended after " +
                         std::to_string(stage_step_) + " of " + std::to_string(stage.steps) +
                         " iterations: " + stage_end_.ended;
      if (!stage_end_.termination.empty()) line += " (Ceres " + stage_end_.termination + ": " + stage_end_.message + ")";
      else if (!stage_end_.message.empty()) line += " (" + stage_end_.message + ")";
      notice(line);
    }
    stage_ends_.push_back(stage_end_);
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
int TrainingStage<Scalar>::index() const { return trainer_.stage_; }
template <typename Scalar>
int TrainingStage<Scalar>::steps() const { return trainer_.options_.stages[trainer_.stage_].steps; }
template <typename Scalar>
int TrainingStage<Scalar>::step() const { return trainer_.stage_step_; }
template <typename Scalar>
fields::Field<Scalar>& TrainingStage<Scalar>::field() { return trainer_.field_; }
template <typename Scalar>
TrainedUnknowns<Scalar>& TrainingStage<Scalar>::unknowns() { return trainer_.unknowns_; }
template <typename Scalar>
std::size_t TrainingStage<Scalar>::term_count() const { return trainer_.terms_.size(); }
template <typename Scalar>
const std::string& TrainingStage<Scalar>::term_name(std::size_t k) const { return trainer_.names_.at(k); }
template <typename Scalar>
const TermPoints& TrainingStage<Scalar>::points(std::size_t k) const { return trainer_.terms_.at(k).points; }
template <typename Scalar>
const autodiff::Matrix<Scalar>& TrainingStage<Scalar>::points_in_scalar(std::size_t k) const {
  return trainer_.terms_.at(k).x;
}
template <typename Scalar>
const Residual& TrainingStage<Scalar>::residual(std::size_t k) const { return *trainer_.terms_.at(k).residual; }
template <typename Scalar>
const autodiff::StreamLayout& TrainingStage<Scalar>::layout(std::size_t k) const {
  return trainer_.terms_.at(k).layout;
}
template <typename Scalar>
double TrainingStage<Scalar>::weight(std::size_t k) const {
  return trainer_.terms_.at(k).term.weight * trainer_.loss_scale(k);
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
  trainer_.step_gradient(gradient);
}
template <typename Scalar>
void TrainingStage<Scalar>::draw_points() { trainer_.resample(); }
template <typename Scalar>
void TrainingStage<Scalar>::update_weights() { trainer_.update_weights(); }
template <typename Scalar>
int TrainingStage<Scalar>::segment_length(int resample_every, bool reweighted) const {
  return trainer_.segment_length(resample_every, reweighted);
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
bool TrainingStage<Scalar>::check_finite(const Scalar* gradient) {
  return trainer_.check_finite(gradient);
}
template <typename Scalar>
bool TrainingStage<Scalar>::check_finite_parameters() { return trainer_.check_finite_parameters(); }
template <typename Scalar>
bool TrainingStage<Scalar>::retry_after_divergence() { return trainer_.retry_after_divergence(); }
template <typename Scalar>
void TrainingStage<Scalar>::end_early(std::string ended, std::string termination, std::string message) {
  trainer_.stage_end_.ended = std::move(ended);
  set_termination(std::move(termination), std::move(message));
}
template <typename Scalar>
void TrainingStage<Scalar>::set_termination(std::string termination, std::string message) {
  trainer_.stage_end_.termination = std::move(termination);
  trainer_.stage_end_.message = std::move(message);
}

template class TrainingStage<float>;
template class TrainingStage<double>;
template class Trainer<float>;
template class Trainer<double>;

}  // namespace nfield::solvers
