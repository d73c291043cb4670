#include "mpi_communicator.hpp"

#include <mpi.h>

#include <algorithm>
#include <climits>
#include <cstdlib>

#include "prt/error.hpp"

namespace prt {

namespace {

void check(int status, const char* call) {
  if (status != MPI_SUCCESS) throw Error(std::string("MPI: ") + call + " failed");
}

// The most bytes one MPI call moves: MPI's counts and displacements are
// ints, so larger messages go in rounds. PRT_MPI_MAX_MESSAGE (bytes) lowers
// it, for tests of the rounds on small meshes. Read on rank 0 only (and
// broadcast): ranks that split messages differently would deadlock.
std::size_t read_max_message() {
  const char* text = std::getenv("PRT_MPI_MAX_MESSAGE");
  if (!text) return static_cast<std::size_t>(INT_MAX);
  char* end = nullptr;
  const unsigned long long value = std::strtoull(text, &end, 10);
  if (end == text || *end != '\0' || value < 64 || value > static_cast<unsigned long long>(INT_MAX))
    throw Error(std::string("PRT_MPI_MAX_MESSAGE=\"") + text +
                "\": expected a byte count from 64 to " + std::to_string(INT_MAX));
  return static_cast<std::size_t>(value);
}

// Adds the wall time of a scope to a counter.
struct Timed {
  double& total;
  double start = MPI_Wtime();
  ~Timed() { total += MPI_Wtime() - start; }
};

// Every rank's message size, on every rank.
std::vector<unsigned long long> all_sizes(std::size_t mine, int ranks) {
  const unsigned long long size = mine;
  std::vector<unsigned long long> sizes(static_cast<std::size_t>(ranks));
  check(MPI_Allgather(&size, 1, MPI_UNSIGNED_LONG_LONG, sizes.data(), 1, MPI_UNSIGNED_LONG_LONG,
                      MPI_COMM_WORLD),
        "MPI_Allgather");
  return sizes;
}

// Messages in rounds: in round j each rank sends bytes [j p, (j + 1) p) of
// its message, p = max_message / ranks, so that one round's bytes (and
// every displacement) fit in an int. Small messages take one round.
struct Rounds {
  std::size_t piece, count;
  Rounds(const std::vector<unsigned long long>& sizes, std::size_t max_message)
      : piece(std::max<std::size_t>(1, max_message / sizes.size())),
        count(std::max<std::size_t>(
            1, (*std::max_element(sizes.begin(), sizes.end()) + piece - 1) / piece)) {}
  // Bytes of a message of `size` sent in round j.
  int part(unsigned long long size, std::size_t j) const {
    const unsigned long long first = static_cast<unsigned long long>(j) * piece;
    return size > first ? static_cast<int>(std::min<unsigned long long>(piece, size - first)) : 0;
  }
};

// Gathers every rank's message in rounds, onto `root` or (root < 0) onto
// every rank.
std::vector<std::vector<char>> gather_in_rounds(const std::vector<char>& mine, int root, int rank,
                                                int ranks, std::size_t max_message) {
  const std::vector<unsigned long long> sizes = all_sizes(mine.size(), ranks);
  const Rounds rounds(sizes, max_message);
  const bool receives = root < 0 || rank == root;
  std::vector<std::vector<char>> out(receives ? sizes.size() : 0);
  for (std::size_t r = 0; r < out.size(); ++r) out[r].resize(sizes[r]);
  std::vector<int> counts(sizes.size()), offsets(sizes.size());
  std::vector<char> round;
  for (std::size_t j = 0; j < rounds.count; ++j) {
    int total = 0;
    for (std::size_t r = 0; r < sizes.size(); ++r)
      offsets[r] = total, counts[r] = rounds.part(sizes[r], j), total += counts[r];
    round.resize(receives ? static_cast<std::size_t>(total) : 0);
    const char* send = mine.data() + std::min(mine.size(), j * rounds.piece);
    const int sending = rounds.part(mine.size(), j);
    if (root < 0)
      check(MPI_Allgatherv(send, sending, MPI_BYTE, round.data(), counts.data(), offsets.data(),
                           MPI_BYTE, MPI_COMM_WORLD),
            "MPI_Allgatherv");
    else
      check(MPI_Gatherv(send, sending, MPI_BYTE, round.data(), counts.data(), offsets.data(),
                        MPI_BYTE, root, MPI_COMM_WORLD),
            "MPI_Gatherv");
    for (std::size_t r = 0; r < out.size(); ++r)
      if (counts[r] > 0)  // a finished message has no byte j * piece
        std::copy_n(round.data() + offsets[r], counts[r], out[r].data() + j * rounds.piece);
  }
  return out;
}

}  // namespace

MpiCommunicator::MpiCommunicator() {
  MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
  MPI_Comm_size(MPI_COMM_WORLD, &size_);
  // A bad value throws on rank 0 alone (one message; prt-mpi then aborts
  // every rank) before any work.
  unsigned long long limit = rank_ == 0 ? read_max_message() : 0;
  check(MPI_Bcast(&limit, 1, MPI_UNSIGNED_LONG_LONG, 0, MPI_COMM_WORLD), "MPI_Bcast");
  max_message_ = static_cast<std::size_t>(limit);
}

void MpiCommunicator::barrier() const {
  const Timed timed{seconds_};
  check(MPI_Barrier(MPI_COMM_WORLD), "MPI_Barrier");
}

std::vector<std::vector<char>> MpiCommunicator::allgather(const std::vector<char>& mine) const {
  const Timed timed{seconds_};
  std::vector<std::vector<char>> all = gather_in_rounds(mine, -1, rank_, size_, max_message_);
  double total = 0;
  for (const auto& part : all) total += double(part.size());
  ++calls_, sent_ += double(mine.size()) * (size_ - 1), received_ += total - double(mine.size());
  return all;
}

std::vector<std::vector<char>> MpiCommunicator::gather(const std::vector<char>& mine,
                                                       int root) const {
  const Timed timed{seconds_};
  std::vector<std::vector<char>> all = gather_in_rounds(mine, root, rank_, size_, max_message_);
  double total = 0;
  for (const auto& part : all) total += double(part.size());
  ++calls_, sent_ += rank_ == root ? 0.0 : double(mine.size());
  received_ += rank_ == root ? total - double(mine.size()) : 0.0;
  return all;
}

void MpiCommunicator::broadcast(std::vector<char>& bytes, int root) const {
  const Timed timed{seconds_};
  unsigned long long size = bytes.size();
  check(MPI_Bcast(&size, 1, MPI_UNSIGNED_LONG_LONG, root, MPI_COMM_WORLD), "MPI_Bcast");
  bytes.resize(size);
  ++calls_, sent_ += rank_ == root ? double(size) * (size_ - 1) : 0.0;
  received_ += rank_ == root ? 0.0 : double(size);
  for (std::size_t first = 0; first < bytes.size(); first += max_message_) {
    const int count = static_cast<int>(std::min(max_message_, bytes.size() - first));
    check(MPI_Bcast(bytes.data() + first, count, MPI_BYTE, root, MPI_COMM_WORLD), "MPI_Bcast");
  }
}

}  // namespace prt
