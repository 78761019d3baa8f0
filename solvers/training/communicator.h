// SPDX-License-Identifier: MIT
//
// Data-parallel training across processes (`mpirun -np R nfield run CONFIG`): the few
// collective operations the trainer needs, behind one small interface, so that the trainer
// and the optimizers hold no MPI code and no #ifdef. A build without MPI (CMake option
// NFIELD_MPI off), or a process not started by an MPI launcher, gets the serial
// communicator: rank 0 of 1, every operation a no-op, and training does what it did before
// data parallelism existed, bit for bit.
//
// How a step is split (solvers/training/trainer.h): every rank draws the whole batch from the
// same stream seeded by training.seed, so all ranks hold the same points; each then runs the
// network passes on its contiguous share of the points (of the groups, for a term over
// groups), with the loss scaled by the whole batch's N, and the shares' losses and gradients
// are summed with allreduce_sum. The step's loss and gradient are the single-process ones
// on the same points up to the order of the sums (round-off), for every R. All ranks then
// apply the same optimizer step to the same sum, so their parameters stay equal without
// being sent. The price is that each rank draws (and keeps) the whole batch: cheap next to
// the network passes for PDE terms, and it keeps a run independent of R but for round-off.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace nfield::solvers {

class Communicator {
 public:
  virtual ~Communicator() = default;

  virtual int rank() const = 0;
  virtual int size() const = 0;

  // Sums n values element by element over all ranks, in place (every rank gets the sum).
  virtual void allreduce_sum(double* data, std::size_t n) = 0;
  virtual void allreduce_sum(float* data, std::size_t n) = 0;
  // Rank 0's n values, copied into every rank's.
  virtual void broadcast(double* data, std::size_t n) = 0;
  virtual void broadcast(float* data, std::size_t n) = 0;
  // Rank r's counts[r] values `mine`, concatenated in rank order into `all` (Σ counts) on
  // every rank.
  virtual void allgather(const double* mine, const std::vector<std::size_t>& counts,
                         double* all) = 0;
  // Whether `flag` is true on any rank (a stop request seen by one rank stops them all).
  virtual bool any(bool flag) = 0;

  // Bytes this process has sent into reductions, broadcasts and gathers so far: the
  // communication volume (each rank's payload; what crosses the network also depends on the
  // MPI library's algorithms).
  std::uint64_t bytes_communicated() const { return bytes_; }

 protected:
  std::uint64_t bytes_ = 0;
};

// Rank 0 of 1: every operation leaves the data as it is.
class SerialCommunicator final : public Communicator {
 public:
  int rank() const override { return 0; }
  int size() const override { return 1; }
  void allreduce_sum(double*, std::size_t) override {}
  void allreduce_sum(float*, std::size_t) override {}
  void broadcast(double*, std::size_t) override {}
  void broadcast(float*, std::size_t) override {}
  void allgather(const double* mine, const std::vector<std::size_t>& counts,
                 double* all) override;
  bool any(bool flag) override { return flag; }
};

// The process's communicator: MPI's world when init_communication started MPI, else a
// serial one.
Communicator& world_communicator();

// Starts MPI when this process was started by an MPI launcher (mpirun, srun: its environment
// says so) and the library was built with MPI; otherwise does nothing, so a plain
// `nfield run` never loads MPI's runtime. Call once, first thing in main; the returned
// object ends MPI when destroyed. Throws std::runtime_error when launched under MPI by a
// build without it (R copies of one serial run would race on the same outputs).
class CommunicationScope {
 public:
  CommunicationScope(int& argc, char**& argv);
  ~CommunicationScope();
  CommunicationScope(const CommunicationScope&) = delete;
  CommunicationScope& operator=(const CommunicationScope&) = delete;

 private:
  bool started_ = false;
};

// Ends every rank's process with `code` (MPI_Abort) when MPI runs; returns otherwise.
void abort_all_ranks(int code);

// Whether the library was built with MPI (NFIELD_MPI).
bool built_with_mpi();

// The contiguous share [first, first + count) of n items that rank `rank` of `size` takes:
// the first n mod size ranks one more than the others.
struct Share {
  std::ptrdiff_t first = 0;
  std::ptrdiff_t count = 0;
};
Share share_of(std::ptrdiff_t n, int rank, int size);

// Whether the ranks stayed in step: rank 0's n values are broadcast, each rank takes the
// largest |its value − rank 0's| over the n, and these are summed over the ranks, so every
// rank gets 0 exactly when all hold rank 0's bits (NaN where any value is NaN). Collective:
// every rank must call it. One process: 0 with no communication. The trainer's θ (the
// network, unknown fields' own networks and unknown constants' ρ at its tail) after
// training: metrics.json `mpi_parameter_spread` (solvers/run/run.cc).
double spread_over_ranks(Communicator& communicator, const double* values, std::size_t n);
double spread_over_ranks(Communicator& communicator, const float* values, std::size_t n);

}  // namespace nfield::solvers
