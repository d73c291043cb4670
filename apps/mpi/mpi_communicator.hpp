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
  // What this rank has exchanged so far: collective calls, bytes it sent and received.
  std::size_t calls() const { return calls_; }
  double bytes_sent() const { return sent_; }
  double bytes_received() const { return received_; }
  double seconds() const { return seconds_; }  // inside MPI calls (waiting included)

 private:
  int rank_ = 0, size_ = 1;
  std::size_t max_message_ = 0;  // bytes one MPI call moves at most
  mutable std::size_t calls_ = 0;
  mutable double sent_ = 0, received_ = 0, seconds_ = 0;
};

}  // namespace prt
