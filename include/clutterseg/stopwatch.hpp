// Per-stage timings for Result::timings_ms (and the baselines' own), in pipeline order.
#pragma once

#include <chrono>

#include "clutterseg/types.hpp"

namespace clutterseg {

// Records the time since the previous mark under a stage name (added to the stage's earlier time when a
// stage runs again in the same frame); total() appends "total".
class Stopwatch {
 public:
  explicit Stopwatch(Timings& out) : out_(out), start_(Clock::now()), last_(start_) {}
  void mark(const char* stage) {
    const auto now = Clock::now();
    const double ms = std::chrono::duration<double, std::milli>(now - last_).count();
    last_ = now;
    for (auto& [name, time] : out_)
      if (name == stage) {
        time += ms;
        return;
      }
    out_.emplace_back(stage, ms);
  }
  void total() { out_.emplace_back("total", std::chrono::duration<double, std::milli>(Clock::now() - start_).count()); }

 private:
  using Clock = std::chrono::steady_clock;
  Timings& out_;
  Clock::time_point start_, last_;
};

}  // namespace clutterseg
