#include "prt/progress.hpp"

#include <unistd.h>

#include <cmath>
#include <cstdio>

#include "prt/error.hpp"

namespace prt {

namespace {
std::atomic<bool> enabled{true};
std::atomic<bool> interrupt{false};
std::atomic<bool> has_sink{false};  // an app's sink wants frequent updates (e.g. a notebook)

void throw_if_interrupted() {
  if (interrupt.load(std::memory_order_relaxed)) throw Error("interrupted");
}
std::mutex sink_mutex;
ProgressSink sink;  // null: draw_bar
}  // namespace

void Progress::set_sink(ProgressSink new_sink) {
  std::lock_guard lock(sink_mutex);
  sink = std::move(new_sink);
  has_sink = static_cast<bool>(sink);
}

void Progress::set_enabled(bool on) {
  enabled = on;
}

void Progress::request_interrupt() {
  interrupt = true;
}

void Progress::clear_interrupt() {
  interrupt = false;
}

void Progress::check_interrupt() {
  throw_if_interrupted();
}

bool Progress::interrupt_requested() {
  return interrupt;
}

Progress::Progress(std::string label, double total, std::string unit, bool quiet)
    : label_(std::move(label)),
      unit_(std::move(unit)),
      total_(total),
      quiet_(quiet || !enabled),
      start_(std::chrono::steady_clock::now()),
      last_draw_(start_) {
  throw_if_interrupted();
}

Progress::~Progress() {
  try {
    finish();
  } catch (...) {  // an app's sink that throws must not end the process here
  }
}

namespace {
void atomic_add(std::atomic<double>& value, double amount) {
  double expected = value.load();
  while (!value.compare_exchange_weak(expected, expected + amount)) {
  }
}
}  // namespace

void Progress::add(double items, double work) {
  throw_if_interrupted();
  atomic_add(done_, items);
  atomic_add(work_, work);
  if (quiet_) return;
  std::unique_lock lock(mutex_, std::try_to_lock);
  if (!lock) return;
  const auto now = std::chrono::steady_clock::now();
  if (now - last_draw_ < std::chrono::milliseconds(has_sink || isatty(2) ? 200 : 5000)) return;
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
  ProgressReport r;
  r.label = label_;
  r.unit = unit_.empty() ? "items" : unit_;
  r.elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  r.done = done_.load();
  r.total = total_;
  r.rate = r.elapsed > 0 ? (unit_.empty() ? r.done : work_.load()) / r.elapsed : 0.0;
  const double item_rate = r.elapsed > 0 ? r.done / r.elapsed : 0.0;
  r.eta = (item_rate > 0 && r.done < r.total) ? (r.total - r.done) / item_rate : 0.0;
  r.final = final;
  ProgressSink current;
  {
    std::lock_guard lock(sink_mutex);
    current = sink;
  }
  // Called outside the lock: a sink may log, or set another sink.
  if (current)
    current(r);
  else
    draw_bar(r);
}

void Progress::draw_bar(const ProgressReport& r) {
  const double fraction = r.total > 0 ? std::min(1.0, r.done / r.total) : 1.0;
  const int width = 30, filled = static_cast<int>(std::lround(fraction * width));
  std::string bar(filled, '#');
  bar.resize(width, '.');
  const bool tty = isatty(2);
  std::fprintf(stderr, "%s%-22s [%s] %5.1f%%  %.3g %s/s  %s %.1fs%s", tty ? "\r" : "",
               r.label.c_str(), bar.c_str(), 100.0 * fraction, r.rate, r.unit.c_str(),
               r.final ? "took" : "ETA", r.final ? r.elapsed : r.eta,
               (r.final || !tty) ? "\n" : "");
  std::fflush(stderr);
}

}  // namespace prt
