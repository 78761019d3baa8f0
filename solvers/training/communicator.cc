// SPDX-License-Identifier: MIT
#include "solvers/training/communicator.h"

#include <algorithm>
#include <climits>
#include <cmath>
#include <cstdlib>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#ifdef NFIELD_WITH_MPI
// MPI's C interface only: the deprecated C++ bindings would need their own library.
#define OMPI_SKIP_MPICXX 1
#define MPICH_SKIP_MPICXX 1
#include <mpi.h>
#endif

namespace nfield::solvers {
namespace {

// The world size an MPI launcher announces in the environment (OpenMPI; MPICH's Hydra and
// Slurm's PMI), 1 when only a PMIx rank says so, or 0 when no launcher started this process.
int launcher_world_size() {
  for (const char* name : {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE"})
    if (const char* value = std::getenv(name)) return std::max(1, std::atoi(value));
  return std::getenv("PMIX_RANK") ? 1 : 0;
}

SerialCommunicator& serial() {
  static SerialCommunicator communicator;
  return communicator;
}

#ifdef NFIELD_WITH_MPI
// MPI counts are ints: long arrays go in pieces.
constexpr std::size_t kPiece = std::size_t{1} << 30;

class MpiCommunicator final : public Communicator {
 public:
  MpiCommunicator() {
    MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
    MPI_Comm_size(MPI_COMM_WORLD, &size_);
  }
  int rank() const override { return rank_; }
  int size() const override { return size_; }
  void allreduce_sum(double* data, std::size_t n) override { reduce(data, n, MPI_DOUBLE); }
  void allreduce_sum(float* data, std::size_t n) override { reduce(data, n, MPI_FLOAT); }
  void broadcast(double* data, std::size_t n) override { bcast(data, n, MPI_DOUBLE); }
  void broadcast(float* data, std::size_t n) override { bcast(data, n, MPI_FLOAT); }

  void allgather(const double* mine, const std::vector<std::size_t>& counts,
                 double* all) override {
    if (counts.size() != static_cast<std::size_t>(size_))
      throw std::invalid_argument("allgather: one count per rank expected");
    std::vector<int> n(size_), displacement(size_);
    std::size_t offset = 0;
    for (int r = 0; r < size_; ++r) {
      if (offset + counts[r] > static_cast<std::size_t>(INT_MAX))
        throw std::runtime_error("allgather: more than 2^31 - 1 values in all");
      n[r] = static_cast<int>(counts[r]);
      displacement[r] = static_cast<int>(offset);
      offset += counts[r];
    }
    bytes_ += counts[rank_] * sizeof(double);
    MPI_Allgatherv(mine, n[rank_], MPI_DOUBLE, all, n.data(), displacement.data(), MPI_DOUBLE,
                   MPI_COMM_WORLD);
  }

  bool any(bool flag) override {
    int value = flag ? 1 : 0;
    bytes_ += sizeof(int);
    MPI_Allreduce(MPI_IN_PLACE, &value, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD);
    return value != 0;
  }

 private:
  template <typename T>
  void reduce(T* data, std::size_t n, MPI_Datatype type) {
    bytes_ += n * sizeof(T);
    for (std::size_t i = 0; i < n; i += kPiece)
      MPI_Allreduce(MPI_IN_PLACE, data + i, static_cast<int>(std::min(kPiece, n - i)), type,
                    MPI_SUM, MPI_COMM_WORLD);
  }
  template <typename T>
  void bcast(T* data, std::size_t n, MPI_Datatype type) {
    if (rank_ == 0) bytes_ += n * sizeof(T);
    for (std::size_t i = 0; i < n; i += kPiece)
      MPI_Bcast(data + i, static_cast<int>(std::min(kPiece, n - i)), type, 0, MPI_COMM_WORLD);
  }

  int rank_ = 0, size_ = 1;
};

std::unique_ptr<MpiCommunicator>& mpi_world() {
  static std::unique_ptr<MpiCommunicator> communicator;
  return communicator;
}
#endif

}  // namespace

void SerialCommunicator::allgather(const double* mine, const std::vector<std::size_t>& counts,
                                   double* all) {
  std::copy(mine, mine + (counts.empty() ? 0 : counts[0]), all);
}

Communicator& world_communicator() {
#ifdef NFIELD_WITH_MPI
  if (mpi_world()) return *mpi_world();
#endif
  return serial();
}

void abort_all_ranks([[maybe_unused]] int code) {
#ifdef NFIELD_WITH_MPI
  if (mpi_world()) MPI_Abort(MPI_COMM_WORLD, code);
#endif
}

bool built_with_mpi() {
#ifdef NFIELD_WITH_MPI
  return true;
#else
  return false;
#endif
}

CommunicationScope::CommunicationScope([[maybe_unused]] int& argc,
                                       [[maybe_unused]] char**& argv) {
  const int launched = launcher_world_size();
  if (launched == 0) return;
#ifdef NFIELD_WITH_MPI
  int provided = 0;
  // Only the main thread calls MPI; OpenMP threads only compute.
  MPI_Init_thread(&argc, &argv, MPI_THREAD_FUNNELED, &provided);
  started_ = true;
  mpi_world() = std::make_unique<MpiCommunicator>();
#else
  if (launched > 1)
    throw std::runtime_error("started by an MPI launcher with " + std::to_string(launched) +
                             " processes, but this nfield was built without MPI (NFIELD_MPI "
                             "off); run it without mpirun, or rebuild with libopenmpi-dev");
#endif
}

CommunicationScope::~CommunicationScope() {
#ifdef NFIELD_WITH_MPI
  if (!started_) return;
  mpi_world().reset();
  MPI_Finalize();
#endif
}

Share share_of(std::ptrdiff_t n, int rank, int size) {
  const std::ptrdiff_t base = n / size, extra = n % size;
  return {rank * base + std::min<std::ptrdiff_t>(rank, extra), base + (rank < extra ? 1 : 0)};
}

namespace {

template <typename Scalar>
double spread(Communicator& communicator, const Scalar* values, std::size_t n) {
  if (communicator.size() == 1) return 0.0;
  std::vector<Scalar> root(values, values + n);
  communicator.broadcast(root.data(), n);
  double largest = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    const double d = std::abs(static_cast<double>(values[i]) - static_cast<double>(root[i]));
    if (std::isnan(d)) largest = d;  // NaN wins: max() would drop it
    else if (!std::isnan(largest)) largest = std::max(largest, d);
  }
  communicator.allreduce_sum(&largest, 1);
  return largest;
}

}  // namespace

double spread_over_ranks(Communicator& communicator, const double* values, std::size_t n) {
  return spread(communicator, values, n);
}
double spread_over_ranks(Communicator& communicator, const float* values, std::size_t n) {
  return spread(communicator, values, n);
}

}  // namespace nfield::solvers
