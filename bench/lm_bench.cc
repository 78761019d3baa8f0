// SPDX-License-Identifier: MIT
//
// One Levenberg–Marquardt iteration, the own method (backend: own: JᵀJ by BLAS syrk, LAPACK
// Cholesky) against Ceres' (backend: ceres, dense_normal_cholesky and dense_qr), measured in
// the same run through the trainer, on two problems:
//   helmholtz_pml  configs/helmholtz_pml.yaml's LM stage: SIREN 3 × 32, complex output
//                  (P = 2,274), 3,000 + 200 + 400 points × 2 components = 7,200 residuals;
//   tanh_5300      a DeepXDE-sized problem: Poisson 2D on a tanh MLP 3 × 50 (P = 5,301),
//                  2,000 interior + 400 boundary points = 2,400 residuals.
// Both in double, from the parameters after --adam Adam steps (300; all backends from the
// same), for --iterations iterations of each backend at one thread and at --threads threads. An iteration's time is the trainer's step
// time (the first includes the stage's first Jacobian, as a stage's first step does);
// "accepted" averages the iterations that lowered the loss (a rejected one costs the own
// method a Cholesky factor only: it keeps JᵀJ, Ceres forms it again). "cpu" is the process's
// CPU time per iteration (all threads): on a busy shared machine the one-thread rows' CPU
// times are the steadier measure of the work.
// Run: build/bench/lm_bench [--iterations K] [--threads T] [--adam S] [--cases a,b] [--no-qr]
//      [--no-one-thread]
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cstdio>
#include <ctime>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>
#include <vector>

#include "solvers/run/run.h"
#include "solvers/training/trainer.h"

namespace {

using namespace nfield;

struct Timing {
  double mean_ms = 0, accepted_ms = 0, cpu_ms = 0;
  int accepted = 0, iterations = 0;
  double final_loss = 0;
};

YAML::Node case_config(const std::string& name) {
  if (name == "helmholtz_pml") return YAML::LoadFile(NFIELD_SOURCE_DIR "/configs/helmholtz_pml.yaml");
  return YAML::Load(
      "problem: poisson\n"
      "domain: {lower: [0, 0], upper: [1, 1]}\n"
      "equation: {source: \"-2*pi^2*sin(pi*x)*sin(pi*y)\", exact: \"sin(pi*x)*sin(pi*y)\"}\n"
      "conditions: [{on: boundary, type: dirichlet, value: \"0\", weight: 10}]\n"
      "field: {type: mlp, activation: tanh, hidden: [50, 50, 50]}\n"
      "training: {seed: 0, precision: double, batch: {interior: 2000, boundary: 400}}\n");
}

// The case's config with one stage in place of its own.
solvers::RunSetup setup_with(const std::string& name, const YAML::Node& stage, int threads) {
  YAML::Node config = case_config(name);
  config["training"]["stages"] = YAML::Node(YAML::NodeType::Sequence);
  config["training"]["stages"].push_back(stage);
  config["training"]["threads"] = threads;
  config["output"] = YAML::Node(YAML::NodeType::Map);
  const auto path = std::filesystem::temp_directory_path() / ("nfield_lm_bench_" + name + ".yaml");
  std::ofstream(path) << config;
  solvers::RunSetup setup = solvers::load_run(path, {});
  std::filesystem::remove(path);
  return setup;
}

// The parameters after `steps` Adam steps (where an LM stage starts in practice: from the
// field's initial parameters LM rejects most of its first steps).
Eigen::VectorXd after_adam(const std::string& name, int steps) {
  const solvers::RunSetup setup = setup_with(
      name, YAML::Load("{optimizer: adam, steps: " + std::to_string(steps) + ", lr: 2.0e-3}"), 0);
  fields::Field<double> field(setup.field);
  solvers::Trainer<double> trainer(*setup.problem, field, setup.training);
  trainer.run({});
  return field.parameters();
}

Timing run(const std::string& name, const Eigen::VectorXd& start, const std::string& backend,
           const std::string& solver, int threads, int iterations) {
  YAML::Node stage;
  stage["optimizer"] = "lm";
  stage["steps"] = iterations;
  stage["backend"] = backend;
  stage["linear_solver"] = solver;
  const solvers::RunSetup setup = setup_with(name, stage, threads);
  fields::Field<double> field(setup.field);
  field.parameters() = start;
  solvers::Trainer<double> trainer(*setup.problem, field, setup.training);
  std::vector<double> losses;
  solvers::Trainer<double>::Callbacks callbacks;
  callbacks.progress = [&](const solvers::Progress& p) { losses.push_back(p.loss); };
  callbacks.stage_begins = [&](const solvers::Progress& p) { losses.push_back(p.loss); };
  const std::clock_t cpu = std::clock();
  trainer.run(callbacks);
  const double cpu_ms = 1e3 * static_cast<double>(std::clock() - cpu) / CLOCKS_PER_SEC;
  Timing t;
  const std::vector<double>& ms = trainer.step_milliseconds();
  t.iterations = static_cast<int>(ms.size());
  for (size_t i = 0; i < ms.size(); ++i) {
    t.mean_ms += ms[i] / ms.size();
    // losses[0] is the stage's start (stage_begins), losses[i + 1] after iteration i.
    if (i + 1 < losses.size() && losses[i + 1] < losses[i]) {
      t.accepted_ms += ms[i];
      ++t.accepted;
    }
  }
  if (t.accepted > 0) t.accepted_ms /= t.accepted;
  t.cpu_ms = cpu_ms / std::max(1, t.iterations);
  t.final_loss = losses.empty() ? NAN : losses.back();
  return t;
}

}  // namespace

int main(int argc, char** argv) {
  int iterations = 4, threads = 2, adam = 300;
  bool qr = true, one_thread = true;
  std::vector<std::string> cases = {"helmholtz_pml", "tanh_5300"};
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--iterations" && i + 1 < argc) iterations = std::atoi(argv[++i]);
    else if (a == "--threads" && i + 1 < argc) threads = std::atoi(argv[++i]);
    else if (a == "--adam" && i + 1 < argc) adam = std::atoi(argv[++i]);
    else if (a == "--no-qr") qr = false;
    else if (a == "--no-one-thread") one_thread = false;
    else if (a == "--cases" && i + 1 < argc) {
      cases.clear();
      std::string list = argv[++i];
      for (size_t at = 0; at <= list.size();) {
        const size_t comma = std::min(list.find(',', at), list.size());
        cases.push_back(list.substr(at, comma - at));
        at = comma + 1;
      }
    } else {
      std::fprintf(stderr, "usage: lm_bench [--iterations K] [--threads T] [--adam S] [--cases helmholtz_pml,tanh_5300] [--no-qr] [--no-one-thread]\n");
      return 2;
    }
  }
  std::printf("%-14s %3s %-28s %10s %12s %9s %8s %12s %8s %12s\n", "case", "thr", "backend",
              "ms/iter", "ms/accepted", "accepted", "ratio", "cpu ms/iter", "cpu rat.", "loss");
  for (const std::string& name : cases) {
    const Eigen::VectorXd start = after_adam(name, adam);
    std::vector<int> counts;
    if (one_thread || threads <= 1) counts.push_back(1);
    if (threads > 1) counts.push_back(threads);
    for (int t : counts) {
      std::vector<std::pair<std::string, std::string>> runs = {
          {"own", "dense_normal_cholesky"}, {"ceres", "dense_normal_cholesky"}};
      if (qr) runs.push_back({"ceres", "dense_qr"});
      double own = 0, own_cpu = 0;
      for (const auto& [backend, solver] : runs) {
        const Timing timing = run(name, start, backend, solver, t, iterations);
        if (backend == "own") {
          own = timing.mean_ms;
          own_cpu = timing.cpu_ms;
        }
        std::printf("%-14s %3d %-28s %10.1f %12.1f %5d/%-3d %8.2f %12.1f %8.2f %12.4e\n",
                    name.c_str(), t, (backend + " " + solver).c_str(), timing.mean_ms,
                    timing.accepted_ms, timing.accepted, timing.iterations, timing.mean_ms / own,
                    timing.cpu_ms, timing.cpu_ms / own_cpu, timing.final_loss);
        std::fflush(stdout);
      }
    }
  }
  return 0;
}
