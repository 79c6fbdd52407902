// A one-line progress bar on a terminal, fed by SimulationOptions::progress.
#pragma once

#include <chrono>
#include <cstdio>

namespace ukdyn::cli {

/// Draws "[=====>    ]  42%  t = 4.2 of 10 s" on a terminal (stderr) for runs longer than
/// `delay`, redrawing at most every `interval`. Does nothing when the stream is not a terminal.
/// update() is cheap between redraws (one clock read), so it can be called after every step.
class ProgressBar {
 public:
  using Clock = std::chrono::steady_clock;

  /// A bar from t_start to t_end on `stream`; drawn only if `enabled` (typically isatty).
  ProgressBar(double t_start, double t_end, bool enabled, std::FILE* stream = stderr,
              Clock::duration delay = std::chrono::seconds(1),
              Clock::duration interval = std::chrono::milliseconds(100));
  ~ProgressBar();
  ProgressBar(const ProgressBar&) = delete;
  ProgressBar& operator=(const ProgressBar&) = delete;

  /// The run has reached time t.
  void update(double t);
  /// Erases the bar (if it was drawn). Called by the destructor too.
  void finish();

  /// True when `stream` is a terminal.
  static bool is_terminal(std::FILE* stream);

 private:
  void draw(double t, Clock::time_point now);

  double t_start_, t_end_;
  bool enabled_;
  std::FILE* stream_;
  Clock::time_point start_, next_draw_;
  Clock::duration interval_;
  bool drawn_ = false;
};

}  // namespace ukdyn::cli
