// The progress bar of `ukdyn run`.
#include "progress.hpp"

#include <algorithm>
#include <string>

#include <unistd.h>

namespace ukdyn::cli {

ProgressBar::ProgressBar(double t_start, double t_end, bool enabled, std::FILE* stream,
                         Clock::duration delay, Clock::duration interval)
    : t_start_(t_start),
      t_end_(t_end),
      enabled_(enabled),
      stream_(stream),
      start_(Clock::now()),
      next_draw_(start_ + delay),
      interval_(interval) {}

ProgressBar::~ProgressBar() { finish(); }

bool ProgressBar::is_terminal(std::FILE* stream) { return ::isatty(::fileno(stream)) == 1; }

void ProgressBar::update(double t) {
  if (!enabled_) return;
  // nothing before the delay has passed, then at most one redraw per interval
  const Clock::time_point now = Clock::now();
  if (now < next_draw_) return;
  next_draw_ = now + interval_;
  draw(t, now);
}

void ProgressBar::draw(double t, Clock::time_point now) {
  constexpr int kWidth = 30;
  const double span = t_end_ - t_start_;
  const double fraction = span > 0 ? std::clamp((t - t_start_) / span, 0.0, 1.0) : 1.0;
  const int filled = int(fraction * kWidth);
  std::string bar(std::size_t(kWidth), ' ');
  std::fill_n(bar.begin(), filled, '=');
  if (filled < kWidth) bar[std::size_t(filled)] = '>';
  const double elapsed = std::chrono::duration<double>(now - start_).count();
  // \r returns to the start of the line, \033[K clears what a longer line left
  std::fprintf(stream_, "\r[%s] %3d%%  t = %.4g of %.4g s  (%.1f s)\033[K", bar.c_str(),
               int(fraction * 100.0), t, t_end_, elapsed);
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
