// Ranks simulated by threads sharing an in-process Communicator, for tests
// that compare a distributed computation with one process bit for bit.
#pragma once
#include <condition_variable>
#include <mutex>
#include <thread>
#include <vector>

#include "prt/communicator.hpp"

namespace prt::test {

// Ranks as threads: every collective is an all-to-all exchange of bytes.
class ThreadGroup {
 public:
  explicit ThreadGroup(int ranks) : slots_(std::size_t(ranks)) {}
  std::vector<std::vector<char>> exchange(int rank, const std::vector<char>& mine) {
    std::unique_lock<std::mutex> lock(mutex_);
    const std::size_t generation = generation_;
    slots_[std::size_t(rank)] = mine;
    if (++arrived_ == int(slots_.size())) {
      published_ = slots_;
      arrived_ = 0;
      ++generation_;
      done_.notify_all();
    } else {
      done_.wait(lock, [&] { return generation_ != generation; });
    }
    return published_;
  }
  int size() const { return int(slots_.size()); }

 private:
  std::mutex mutex_;
  std::condition_variable done_;
  std::vector<std::vector<char>> slots_, published_;
  int arrived_ = 0;
  std::size_t generation_ = 0;
};

class ThreadCommunicator final : public Communicator {
 public:
  ThreadCommunicator(ThreadGroup& group, int rank) : group_(group), rank_(rank) {}
  int rank() const override { return rank_; }
  int size() const override { return group_.size(); }
  void barrier() const override { group_.exchange(rank_, {}); }
  std::vector<std::vector<char>> allgather(const std::vector<char>& mine) const override {
    return group_.exchange(rank_, mine);
  }
  std::vector<std::vector<char>> gather(const std::vector<char>& mine, int root) const override {
    auto all = group_.exchange(rank_, mine);
    return rank_ == root ? all : std::vector<std::vector<char>>{};
  }
  void broadcast(std::vector<char>& bytes, int root) const override {
    bytes = group_.exchange(rank_, rank_ == root ? bytes : std::vector<char>{})[std::size_t(root)];
  }

 private:
  ThreadGroup& group_;
  int rank_;
};

// Runs work(comm) on `ranks` threads, each with its own rank of one group.
template <class Work>
void run_on_ranks(int ranks, const Work& work) {
  ThreadGroup group(ranks);
  std::vector<std::thread> threads;
  for (int r = 0; r < ranks; ++r)
    threads.emplace_back([&, r] {
      ThreadCommunicator comm(group, r);
      work(static_cast<const Communicator&>(comm));
    });
  for (auto& t : threads) t.join();
}

}  // namespace prt::test
