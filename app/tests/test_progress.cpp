// SPDX-License-Identifier: BSD-3-Clause
// The progress display of `ukdyn run` (app/progress.cpp): the bar on a terminal and the plain
// log line elsewhere, with step size, method and ETA.
#include <chrono>
#include <cstdio>
#include <string>

#include <gtest/gtest.h>

#include "progress.hpp"

namespace ukdyn::cli {
namespace {

// everything written to a temporary stream
std::string text_of(std::FILE* f) {
  std::fflush(f);
  std::rewind(f);
  std::string out;
  char buf[512];
  while (std::fgets(buf, sizeof buf, f)) out += buf;
  return out;
}

ProgressReport at(double t, double step, long steps, Integrator m = Integrator::kDopri5) {
  ProgressReport p;
  p.t = t;
  p.step = step;
  p.steps = steps;
  p.integrator = m;
  return p;
}

using Duration = ProgressBar::Clock::duration;

TEST(Progress, LogModeWritesAPlainLineWithStepMethodStepsAndEta) {
  std::FILE* f = std::tmpfile();
  ASSERT_NE(f, nullptr);
  {
    ProgressBar log(0.0, 5.0, ProgressBar::Mode::kLog, f, Duration::zero(), Duration::zero());
    log.update(at(2.5, 1.25e-6, 1234, Integrator::kBDF));
  }
  const std::string out = text_of(f);
  std::fclose(f);
  EXPECT_EQ(out.find("ukdyn: t = 2.5 of 5 s (50%), step 1.25e-06 s (bdf), 1234 steps, "), 0u)
      << out;
  EXPECT_NE(out.find("ETA "), std::string::npos) << out;
  EXPECT_EQ(out.back(), '\n');
  EXPECT_EQ(out.find('\r'), std::string::npos) << "no terminal control characters in a log";
}

TEST(Progress, LogModeWritesOneLinePerInterval) {
  std::FILE* f = std::tmpfile();
  ASSERT_NE(f, nullptr);
  {
    // a 20 ms delay and interval over 110 ms of updates, 1 ms apart on the clock the test
    // gives (not the machine's): a line at 20, 40, 60, 80 and 100 ms
    const auto interval = std::chrono::milliseconds(20);
    ProgressBar log(0.0, 1.0, ProgressBar::Mode::kLog, f, interval, interval);
    const auto t0 = ProgressBar::Clock::now();
    for (int i = 1; i <= 110; ++i)
      log.update(at(i * 1e-3, 1e-3, i), t0 + std::chrono::milliseconds(i));
  }
  const std::string out = text_of(f);
  std::fclose(f);
  long lines = 0;
  for (char c : out) lines += c == '\n';
  EXPECT_EQ(lines, 5) << out;
}

TEST(Progress, BarModeShowsStepAndEtaAndIsErased) {
  std::FILE* f = std::tmpfile();
  ASSERT_NE(f, nullptr);
  {
    ProgressBar bar(0.0, 10.0, ProgressBar::Mode::kBar, f, Duration::zero(), Duration::zero());
    bar.update(at(4.2, 1e-3, 42));
  }
  const std::string out = text_of(f);
  std::fclose(f);
  EXPECT_NE(out.find("42%  t = 4.2 of 10 s  h = 0.001 s dopri5  ("), std::string::npos) << out;
  EXPECT_NE(out.find("ETA "), std::string::npos) << out;
  EXPECT_EQ(out.substr(out.size() - 4), "\r\033[K") << "erased at the end";
}

TEST(Progress, OffModeWritesNothing) {
  std::FILE* f = std::tmpfile();
  ASSERT_NE(f, nullptr);
  {
    ProgressBar none(0.0, 1.0, ProgressBar::Mode::kOff, f, Duration::zero(), Duration::zero());
    none.update(at(0.5, 1e-3, 1));
  }
  EXPECT_EQ(text_of(f), "");
  std::fclose(f);
}

TEST(Progress, DurationText) {
  EXPECT_EQ(ProgressBar::duration_text(12.4), "12 s");
  EXPECT_EQ(ProgressBar::duration_text(200.0), "3 min 20 s");
  EXPECT_EQ(ProgressBar::duration_text(7500.0), "2 h 5 min");
  EXPECT_EQ(ProgressBar::duration_text(-1.0), "?");
  // (an ETA of 7.7e12 s printed "-2147483648 h": an int's overflow)
  EXPECT_EQ(ProgressBar::duration_text(3600.0 * 99999.5), "99999 h 30 min");
  EXPECT_EQ(ProgressBar::duration_text(7.73e12), "2.1e+09 h");
}

}  // namespace
}  // namespace ukdyn::cli
