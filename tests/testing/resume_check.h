// SPDX-License-Identifier: MIT
//
// The trainer tests' resume check: a run stopped after some steps, checkpointed (field and
// trainer state), loaded into a fresh field and trainer and run to its end must end with the
// parameters, bit for bit, of the same run never stopped. `more` adds a test's own checks
// (strategies' state, unknowns' trajectories) on the two finished runs. Call it inside
// ASSERT_NO_FATAL_FAILURE: its assertions return from it, not from the test.
#pragma once

#include <gtest/gtest.h>

#include <filesystem>
#include <functional>

#include "fields/field_io.h"
#include "io/hdf5_file.h"
#include "solvers/run/run_setup.h"
#include "solvers/training/trainer.h"

namespace nfield::testutil {

template <typename Scalar>
struct FinishedRuns {
  const fields::Field<Scalar>& whole_field;
  const solvers::Trainer<Scalar>& whole;
  const fields::Field<Scalar>& resumed_field;
  const solvers::Trainer<Scalar>& resumed;
};

template <typename Scalar>
void expect_resume_is_bit_exact(const solvers::RunSetup& setup, const std::filesystem::path& checkpoint,
                                long stop_after,
                                const std::function<void(const FinishedRuns<Scalar>&)>& more = {}) {
  using solvers::Trainer;
  fields::Field<Scalar> full(setup.field);
  Trainer<Scalar> whole(*setup.problem, full, setup.training);
  ASSERT_TRUE(whole.run({}));
  {
    fields::Field<Scalar> first(setup.field);
    Trainer<Scalar> trainer(*setup.problem, first, setup.training);
    typename Trainer<Scalar>::Callbacks callbacks;
    callbacks.stop_requested = [&trainer, stop_after] { return trainer.step() >= stop_after; };
    ASSERT_FALSE(trainer.run(callbacks));
    io::H5Writer file(checkpoint);
    fields::save_field(file, first);
    trainer.save_state(file);
    file.commit();
  }
  const io::H5Reader file(checkpoint);
  fields::Field<Scalar> resumed = fields::load_field<Scalar>(file);
  Trainer<Scalar> trainer(*setup.problem, resumed, setup.training);
  trainer.load_state(file);
  ASSERT_TRUE(trainer.run({}));
  ASSERT_EQ(resumed.parameter_count(), full.parameter_count());
  for (Eigen::Index i = 0; i < full.parameters().size(); ++i)
    ASSERT_EQ(resumed.parameters()(i), full.parameters()(i)) << "parameter " << i;
  if (more) more({full, whole, resumed, trainer});
}

}  // namespace nfield::testutil
