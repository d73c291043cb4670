#include "mpi_communicator.hpp"

#include <mpi.h>

#include <climits>
#include <numeric>

#include "prt/error.hpp"

namespace prt {

namespace {

int message_size(std::size_t bytes) {
  if (bytes > static_cast<std::size_t>(INT_MAX))
    throw Error("MPI: a message of " + std::to_string(bytes) + " bytes is over MPI's 2 GB limit");
  return static_cast<int>(bytes);
}

void check(int status, const char* call) {
  if (status != MPI_SUCCESS) throw Error(std::string("MPI: ") + call + " failed");
}

// Adds the wall time of a scope to a counter.
struct Timed {
  double& total;
  double start = MPI_Wtime();
  ~Timed() { total += MPI_Wtime() - start; }
};

// Splits the received bytes by the senders' counts.
std::vector<std::vector<char>> split(const std::vector<char>& all, const std::vector<int>& counts,
                                     const std::vector<int>& offsets) {
  std::vector<std::vector<char>> out(counts.size());
  for (std::size_t r = 0; r < counts.size(); ++r)
    out[r].assign(all.begin() + offsets[r], all.begin() + offsets[r] + counts[r]);
  return out;
}

}  // namespace

MpiCommunicator::MpiCommunicator() {
  MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
  MPI_Comm_size(MPI_COMM_WORLD, &size_);
}

void MpiCommunicator::barrier() const {
  const Timed timed{seconds_};
  check(MPI_Barrier(MPI_COMM_WORLD), "MPI_Barrier");
}

std::vector<std::vector<char>> MpiCommunicator::allgather(const std::vector<char>& mine) const {
  const Timed timed{seconds_};
  const int count = message_size(mine.size());
  std::vector<int> counts(size_), offsets(size_, 0);
  check(MPI_Allgather(&count, 1, MPI_INT, counts.data(), 1, MPI_INT, MPI_COMM_WORLD),
        "MPI_Allgather");
  std::size_t total = 0;
  for (int r = 0; r < size_; ++r) offsets[r] = message_size(total), total += counts[r];
  message_size(total);
  std::vector<char> all(total);
  ++calls_, sent_ += double(mine.size()) * (size_ - 1), received_ += double(total - mine.size());
  check(MPI_Allgatherv(mine.data(), count, MPI_BYTE, all.data(), counts.data(), offsets.data(),
                       MPI_BYTE, MPI_COMM_WORLD),
        "MPI_Allgatherv");
  return split(all, counts, offsets);
}

std::vector<std::vector<char>> MpiCommunicator::gather(const std::vector<char>& mine,
                                                       int root) const {
  const Timed timed{seconds_};
  const int count = message_size(mine.size());
  std::vector<int> counts(size_), offsets(size_, 0);
  check(MPI_Gather(&count, 1, MPI_INT, counts.data(), 1, MPI_INT, root, MPI_COMM_WORLD),
        "MPI_Gather");
  std::size_t total = 0;
  if (rank_ == root)
    for (int r = 0; r < size_; ++r) offsets[r] = message_size(total), total += counts[r];
  std::vector<char> all(rank_ == root ? total : 0);
  ++calls_, sent_ += rank_ == root ? 0.0 : double(mine.size());
  received_ += rank_ == root ? double(total - mine.size()) : 0.0;
  check(MPI_Gatherv(mine.data(), count, MPI_BYTE, all.data(), counts.data(), offsets.data(),
                    MPI_BYTE, root, MPI_COMM_WORLD),
        "MPI_Gatherv");
  if (rank_ != root) return {};
  return split(all, counts, offsets);
}

void MpiCommunicator::broadcast(std::vector<char>& bytes, int root) const {
  const Timed timed{seconds_};
  unsigned long long size = bytes.size();
  check(MPI_Bcast(&size, 1, MPI_UNSIGNED_LONG_LONG, root, MPI_COMM_WORLD), "MPI_Bcast");
  bytes.resize(size);
  ++calls_, sent_ += rank_ == root ? double(size) * (size_ - 1) : 0.0;
  received_ += rank_ == root ? 0.0 : double(size);
  check(MPI_Bcast(bytes.data(), message_size(size), MPI_BYTE, root, MPI_COMM_WORLD), "MPI_Bcast");
}

}  // namespace prt
