// SPDX-License-Identifier: BSD-3-Clause
// The progress display of `ukdyn run`.
#include "progress.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include <unistd.h>

namespace ukdyn::cli {

namespace {
using std::chrono::milliseconds;
using std::chrono::seconds;
// the rate behind the ETA is measured over one to two of these
constexpr ProgressBar::Clock::duration kRateWindow = seconds(3);

ProgressBar::Clock::duration or_default(ProgressBar::Clock::duration d,
                                        ProgressBar::Clock::duration fallback) {
  return d < ProgressBar::Clock::duration::zero() ? fallback : d;
}
}  // namespace

ProgressBar::ProgressBar(double t_start, double t_end, Mode mode, std::FILE* stream,
                         Clock::duration delay, Clock::duration interval)
    : t_start_(t_start),
      t_end_(t_end),
      mode_(mode),
      stream_(stream),
      start_(Clock::now()),
      next_draw_(start_ + or_default(delay, mode == Mode::kLog ? Clock::duration(seconds(5))
                                                               : Clock::duration(seconds(1)))),
      interval_(or_default(interval, mode == Mode::kLog ? Clock::duration(seconds(5))
                                                        : Clock::duration(milliseconds(100)))),
      older_{start_, t_start},
      newer_{start_, t_start} {}

ProgressBar::~ProgressBar() { finish(); }

ProgressBar::Mode ProgressBar::mode_for(std::FILE* stream) {
  return ::isatty(::fileno(stream)) == 1 ? Mode::kBar : Mode::kLog;
}

std::string ProgressBar::duration_text(double s) {
  if (!(s >= 0.0) || !std::isfinite(s)) return "?";
  char buf[48];
  if (s < 60.0) {
    std::snprintf(buf, sizeof buf, "%.0f s", s);
  } else if (s < 3600.0) {
    std::snprintf(buf, sizeof buf, "%d min %d s", int(s / 60.0), int(std::fmod(s, 60.0)));
  } else if (s < 3600.0 * 1e5) {
    std::snprintf(buf, sizeof buf, "%d h %d min", int(s / 3600.0),
                  int(std::fmod(s, 3600.0) / 60.0));
  } else {
    // (beyond 100,000 h in hours to 2 digits: "ETA -2147483648 h" overflowed an int, u22 05)
    std::snprintf(buf, sizeof buf, "%.2g h", s / 3600.0);
  }
  return buf;
}

void ProgressBar::update(const ProgressReport& p) {
  if (mode_ == Mode::kOff) return;
  update(p, Clock::now());
}

void ProgressBar::update(const ProgressReport& p, Clock::time_point now) {
  if (mode_ == Mode::kOff) return;
  // nothing before the delay has passed, then at most one output per interval
  if (now < next_draw_) return;
  next_draw_ = now + interval_;
  draw(p, now);
}

double ProgressBar::eta(double t, Clock::time_point now) {
  // move the anchors a window on: the rate spans one to two windows of the recent past
  if (now - newer_.wall >= kRateWindow) {
    older_ = newer_;
    newer_ = {now, t};
  }
  const double wall = std::chrono::duration<double>(now - older_.wall).count();
  const double rate = wall > 0 ? (t - older_.t) / wall : 0.0;
  return rate > 0 ? (t_end_ - t) / rate : -1.0;
}

void ProgressBar::draw(const ProgressReport& p, Clock::time_point now) {
  const double span = t_end_ - t_start_;
  const double fraction = span > 0 ? std::clamp((p.t - t_start_) / span, 0.0, 1.0) : 1.0;
  const double elapsed = std::chrono::duration<double>(now - start_).count();
  const std::string eta_text = duration_text(eta(p.t, now));
  if (mode_ == Mode::kLog) {
    std::fprintf(stream_,
                 "ukdyn: t = %.6g of %.6g %s (%d%%), step %.3g %s (%s), %ld steps, %.1f s "
                 "elapsed, ETA %s\n",
                 p.t, t_end_, time_unit_.c_str(), int(fraction * 100.0), p.step, time_unit_.c_str(),
                 to_string(p.integrator), p.steps, elapsed, eta_text.c_str());
    std::fflush(stream_);
    return;
  }
  constexpr int kWidth = 30;
  const int filled = int(fraction * kWidth);
  std::string bar(std::size_t(kWidth), ' ');
  std::fill_n(bar.begin(), filled, '=');
  if (filled < kWidth) bar[std::size_t(filled)] = '>';
  // \r returns to the start of the line, \033[K clears what a longer line left
  std::fprintf(stream_, "\r[%s] %3d%%  t = %.4g of %.4g %s  h = %.2g %s %s  (%.1f s, ETA %s)\033[K",
               bar.c_str(), int(fraction * 100.0), p.t, t_end_, time_unit_.c_str(), p.step,
               time_unit_.c_str(), to_string(p.integrator), elapsed, eta_text.c_str());
  std::fflush(stream_);
  drawn_ = true;
}

void ProgressBar::finish() {
  if (!drawn_) return;
  std::fputs("\r\033[K", stream_);
  std::fflush(stream_);
  drawn_ = false;
}

}  // namespace ukdyn::cli
