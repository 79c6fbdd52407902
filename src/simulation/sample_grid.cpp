// SPDX-License-Identifier: BSD-3-Clause
// The sample times of a run on demand (simulation/sample_grid.hpp): the regular grid t_start + i ·
// every and the few irregular times, merged as sorting them all would, without storing the grid.
#include "simulation/sample_grid.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>
#include "ukdyn/core/format.hpp"

namespace ukdyn::detail {
namespace {

std::string g(double v) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  return buf;
}

// a sample count: the integer when it fits, else %.3g
std::string count_text(double c) {
  if (c < 1e18) return format_number(static_cast<long long>(c));
  return g(c);
}

}  // namespace

SampleGrid::SampleGrid(const SimulationOptions& o, double max_samples, const char* bound_name)
    : a_(o.t_start), every_(o.output_every) {
  const double b = o.t_end;
  const double eps = 1e-12 * std::max({1.0, std::abs(a_), std::abs(b)});
  const std::string options =
      "output_every = " + g(every_) + ", t_start = " + g(a_) + ", t_end = " + g(b);

  // the irregular times inside [t_start, t_end], sorted: t_start, output_at, t_end
  std::vector<double> irregular = o.output_at;
  irregular.push_back(a_);
  irregular.push_back(b);
  irregular.erase(
      std::remove_if(irregular.begin(), irregular.end(),
                     [&](double t) { return !(t >= a_ && t <= b) || !std::isfinite(t); }),
      irregular.end());
  std::sort(irregular.begin(), irregular.end());

  // the regular count, formed in double: refused above the bound before it becomes an integer
  if (every_ > 0.0) {
    const double count = (b - a_) / every_ * (1 + 1e-12);
    const double total = std::floor(count) + double(irregular.size());
    if (!(total <= max_samples)) {
      throw SettingError(
          "output_every",
          "ukdyn::simulate: the output grid (" + options + ") has " + count_text(total) +
              " samples, more than the bound of " + count_text(std::floor(max_samples)) + " " +
              bound_name +
              " (docs/simulation.md, \"Sample grid and streaming\"): use a larger "
              "output_every (model file: output: every:) or a shorter run (t_end, --t-end)");
    }
    if (!(every_ > 2.0 * eps)) {
      throw SettingError("output_every",
                         "ukdyn::simulate: the sample spacing output_every = " + g(every_) +
                             " is below the resolution of the sample times, 2e-12 · max(1, "
                             "|t_start|, |t_end|) = " +
                             g(2.0 * eps) + " (" + options + "): consecutive samples would merge");
    }
    last_ = long(std::floor(count));
    while (last_ > 0 && !(grid(last_) <= b)) --last_;
  } else if (!(double(irregular.size()) <= max_samples)) {
    throw SettingError("output_at", "ukdyn::simulate: output_at has " +
                                        count_text(double(irregular.size())) +
                                        " samples, more than the bound of " +
                                        count_text(std::floor(max_samples)) + " " + bound_name);
  }

  // the merge, as a sort of all the times followed by "keep t if t − (last kept) > eps" would
  // do it: a regular time is > 2 eps after the previous one, so only the first regular time
  // after a kept irregular one can be dropped; irregular times are judged one by one
  bool any = false;
  double last_kept = 0.0;
  long next = 1;         // the first regular time not merged yet
  std::size_t kept = 0;  // regular times kept so far
  // the regular times next … j (all before the next irregular time)
  const auto merge_regular = [&](long j) {
    if (j < next) return;
    if (any && !(grid(next) - last_kept > eps)) {
      dropped_.push_back(next - 1 - long(dropped_.size()));  // (rank formula of operator[])
    } else {
      ++kept;
      last_kept = grid(next);
      any = true;
    }
    kept += std::size_t(j - next);
    if (j > next) last_kept = grid(j);
    next = j + 1;
  };
  for (const double t : irregular) {
    // the last regular index with a time < t (a regular time equal to t follows it)
    long j = 0;
    if (last_ > 0) {
      j = std::clamp(long(std::floor((t - a_) / every_)), 0L, last_);
      while (j < last_ && grid(j + 1) < t) ++j;
      while (j >= 1 && !(grid(j) < t)) --j;
    }
    merge_regular(j);
    if (!any || t - last_kept > eps) {
      extra_at_.push_back(extra_.size() + kept);
      extra_.push_back(t);
      last_kept = t;
      any = true;
    }
  }
  merge_regular(last_);
  size_ = extra_.size() + kept;
}

double SampleGrid::operator[](std::size_t i) const {
  const auto it = std::lower_bound(extra_at_.begin(), extra_at_.end(), i);
  if (it != extra_at_.end() && *it == i) return extra_[std::size_t(it - extra_at_.begin())];
  // the r-th regular time kept (0-based): index 1 + r + (dropped indices at or before it)
  const long r = long(i) - long(it - extra_at_.begin());
  const long before =
      long(std::upper_bound(dropped_.begin(), dropped_.end(), r) - dropped_.begin());
  return grid(1 + r + before);
}

std::size_t SampleGrid::upper_bound(double t) const {
  std::size_t lo = 0, hi = size_;
  while (lo < hi) {
    const std::size_t mid = lo + (hi - lo) / 2;
    if ((*this)[mid] <= t) {
      lo = mid + 1;
    } else {
      hi = mid;
    }
  }
  return lo;
}

}  // namespace ukdyn::detail
