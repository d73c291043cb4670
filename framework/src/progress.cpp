#include "prt/progress.hpp"

#include <unistd.h>

#include <cmath>
#include <cstdio>

namespace prt {

namespace {
std::atomic<bool> enabled{true};
}  // namespace

void Progress::set_enabled(bool on) {
  enabled = on;
}

Progress::Progress(std::string label, double total, std::string unit, bool quiet)
    : label_(std::move(label)),
      unit_(std::move(unit)),
      total_(total),
      quiet_(quiet || !enabled),
      start_(std::chrono::steady_clock::now()),
      last_draw_(start_) {}

Progress::~Progress() {
  finish();
}

namespace {
void atomic_add(std::atomic<double>& value, double amount) {
  double expected = value.load();
  while (!value.compare_exchange_weak(expected, expected + amount)) {
  }
}
}  // namespace

void Progress::add(double items, double work) {
  atomic_add(done_, items);
  atomic_add(work_, work);
  if (quiet_) return;
  std::unique_lock lock(mutex_, std::try_to_lock);
  if (!lock) return;
  const auto now = std::chrono::steady_clock::now();
  if (now - last_draw_ < std::chrono::milliseconds(isatty(2) ? 200 : 5000)) return;
  last_draw_ = now;
  draw(false);
}

void Progress::finish() {
  if (finished_) return;
  finished_ = true;
  if (!quiet_) {
    std::lock_guard lock(mutex_);
    draw(true);
  }
}

void Progress::draw(bool final) {
  const double elapsed =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  const double done = done_.load();
  const double fraction = total_ > 0 ? std::min(1.0, done / total_) : 1.0;
  const double rate = elapsed > 0 ? (unit_.empty() ? done : work_.load()) / elapsed : 0.0;
  const double item_rate = elapsed > 0 ? done / elapsed : 0.0;
  const double eta = (item_rate > 0 && fraction < 1) ? (total_ - done) / item_rate : 0.0;
  const int width = 30, filled = static_cast<int>(std::lround(fraction * width));
  std::string bar(filled, '#');
  bar.resize(width, '.');
  const bool tty = isatty(2);
  std::fprintf(stderr, "%s%-22s [%s] %5.1f%%  %.3g %s/s  %s %.1fs%s", tty ? "\r" : "",
               label_.c_str(), bar.c_str(), 100.0 * fraction, rate,
               unit_.empty() ? "items" : unit_.c_str(), final ? "took" : "ETA",
               final ? elapsed : eta, (final || !tty) ? "\n" : "");
  std::fflush(stderr);
}

}  // namespace prt
