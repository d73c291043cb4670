// A progress bar on stderr for long work: fraction, rate and ETA.
#pragma once
#include <atomic>
#include <chrono>
#include <functional>
#include <mutex>
#include <string>

namespace prt {

// One progress update, as a sink receives it.
struct ProgressReport {
  std::string label, unit;  // unit: of the rate ("rays"), or "items"
  double done = 0, total = 0;
  double rate = 0;              // units per second
  double elapsed = 0, eta = 0;  // seconds
  bool final = false;           // the last report of this bar
};
using ProgressSink = std::function<void(const ProgressReport&)>;

class Progress {
 public:
  // Where every bar of the process reports: the app's callback, or (null,
  // the default) a bar on standard error, redrawn in place on a terminal.
  static void set_sink(ProgressSink sink);
  static void draw_bar(const ProgressReport& report);

  // Counts `total` items; the rate shown is of `rate_unit` (e.g. "rays"), fed
  // by the second argument of add(), or of the items when rate_unit is empty.
  // Quiet bars print nothing.
  Progress(std::string label, double total, std::string rate_unit = "", bool quiet = false);
  ~Progress();
  void add(double items, double work = 0);
  // Switches every progress bar of the process off or on (the CLI's --quiet).
  static void set_enabled(bool enabled);
  // Cooperative interruption (Ctrl-C in the Python module): once requested,
  // the next bar made or advanced, on any thread, throws prt::Error
  // "interrupted"; the work unwinds as from any other error, writing nothing.
  static void request_interrupt();
  static void clear_interrupt();
  static bool interrupt_requested();
  // Throws the same where long work has no bar (e.g. clustering iterations).
  static void check_interrupt();
  void finish();

 private:
  void draw(bool final);
  std::string label_, unit_;
  double total_;
  bool quiet_, finished_ = false;
  std::atomic<double> done_{0}, work_{0};
  std::chrono::steady_clock::time_point start_, last_draw_;
  std::mutex mutex_;
};

// Wall-clock seconds since construction.
class Stopwatch {
 public:
  Stopwatch() : start_(std::chrono::steady_clock::now()) {}
  double seconds() const {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  }

 private:
  std::chrono::steady_clock::time_point start_;
};

}  // namespace prt
