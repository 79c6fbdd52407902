// SPDX-License-Identifier: BSD-3-Clause
// Progress of `ukdyn run`, fed by SimulationOptions::progress: a one-line bar on a terminal, or
// a plain log line every few seconds when stderr is not one (batch jobs, pipes, CI logs).
#pragma once

#include <chrono>
#include <cstdio>
#include <string>
#include <utility>

#include <ukdyn/simulation/simulate.hpp>

namespace ukdyn::cli {

/// On a terminal, draws "[=====>    ]  42%  t = 4.2 of 10 s  h = 1e-03 s dopri5  (3.1 s, ETA
/// 4 s)" on stderr for runs longer than `delay`, redrawing at most every `interval`. Otherwise
/// (Mode::kLog) writes a line "ukdyn: t = 4.2 of 10 s (42%), step 1e-03 s (dopri5), 1234
/// steps, 5.0 s elapsed, ETA 7 s" every `interval` (5 s by default). update() is cheap between
/// outputs (one clock read), so it can be called after every step.
///
/// The ETA extrapolates the rate of simulated time over the last 3–6 s of wall time (not since
/// the start), so a run that turns slow — a stiff phase — shows it within seconds.
class ProgressBar {
 public:
  using Clock = std::chrono::steady_clock;
  enum class Mode {
    kOff,  ///< nothing
    kBar,  ///< a bar redrawn in place (terminals)
    kLog,  ///< a plain line every interval (files, pipes)
  };

  /// Progress from t_start to t_end on `stream`. The defaults of delay and interval are those
  /// of the mode (kBar: 1 s and 0.1 s; kLog: 5 s and 5 s) when given as negative.
  ProgressBar(double t_start, double t_end, Mode mode, std::FILE* stream = stderr,
              Clock::duration delay = Clock::duration(-1),
              Clock::duration interval = Clock::duration(-1));
  ~ProgressBar();
  ProgressBar(const ProgressBar&) = delete;
  ProgressBar& operator=(const ProgressBar&) = delete;

  /// The run has reached p.t with step p.step (at Clock::now()).
  void update(const ProgressReport& p);
  /// The same at the wall-clock time `now` (later than the previous call's): what the tests
  /// drive, so that no test depends on the speed of the machine.
  void update(const ProgressReport& p, Clock::time_point now);
  /// Erases the bar (if it was drawn). Called by the destructor too.
  void finish();
  /// The unit of the simulated time t and the step h ("s" unless set: the model's, UnitSystem;
  /// the wall times stay in s).
  void set_time_unit(std::string unit) { time_unit_ = std::move(unit); }

  /// kBar when `stream` is a terminal, else kLog.
  static Mode mode_for(std::FILE* stream);
  /// "12 s", "3 min 20 s", "2 h 5 min", or "?" for a negative or non-finite time.
  static std::string duration_text(double seconds);

 private:
  void draw(const ProgressReport& p, Clock::time_point now);
  // seconds of wall time still needed at the recent rate, or −1 when unknown
  double eta(double t, Clock::time_point now);

  double t_start_, t_end_;
  std::string time_unit_ = "s";  // the simulated time's unit (set_time_unit)
  Mode mode_;
  std::FILE* stream_;
  Clock::time_point start_, next_draw_;
  Clock::duration interval_;
  bool drawn_ = false;
  // (wall time, simulated time) at two moments a window apart: the rate for the ETA
  struct Anchor {
    Clock::time_point wall;
    double t;
  };
  Anchor older_, newer_;
};

}  // namespace ukdyn::cli
