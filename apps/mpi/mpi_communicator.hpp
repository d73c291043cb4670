// prt's Communicator over MPI_COMM_WORLD (the framework itself does not link MPI).
#pragma once
#include "prt/communicator.hpp"

namespace prt {

class MpiCommunicator final : public Communicator {
 public:
  MpiCommunicator();
  int rank() const override { return rank_; }
  int size() const override { return size_; }
  void barrier() const override;
  std::vector<std::vector<char>> allgather(const std::vector<char>& mine) const override;
  std::vector<std::vector<char>> gather(const std::vector<char>& mine, int root) const override;
  void broadcast(std::vector<char>& bytes, int root) const override;

 private:
  int rank_ = 0, size_ = 1;
};

}  // namespace prt
