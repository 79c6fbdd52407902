// SPDX-License-Identifier: BSD-3-Clause
// Internal: the sample times of a run, computed on demand (index → time) instead of stored, and
// ranges of them handed to the integrators. Not installed.
#pragma once

#include <cstddef>
#include <iterator>
#include <vector>

#include "ukdyn/simulation/simulate.hpp"

namespace ukdyn::detail {

// The sample times of a run: t_start, t_start + i · output_every (i = 1, 2, … while <= t_end),
// the output_at inside [t_start, t_end], and t_end; sorted, and a time within
// eps = 1e-12 · max(1, |t_start|, |t_end|) after the previous time kept is dropped. Exactly the
// times (bit for bit) of the former vector built by sorting all of them, but stored as the
// regular grid plus the few irregular times (output_at, t_end) and the grid points they drop:
// memory O(output_at.size()), time[i] in O(log output_at.size()).
//
// The constructor refuses (SettingError for output_every, or output_at without it, naming
// output_every, t_start, t_end, the count and the bound) a grid of more than `max_samples` samples,
// before any time is computed (the count of the regular part is formed in double, so 1e300 / 0.01
// is refused, not overflowed), and a spacing output_every at or below 2 eps, where consecutive
// times would merge.
class SampleGrid {
 public:
  SampleGrid(const SimulationOptions& o, double max_samples, const char* bound_name);

  std::size_t size() const { return size_; }
  // time of sample i < size()
  double operator[](std::size_t i) const;
  // the first index whose time is > t (size() if none): O(log size())
  std::size_t upper_bound(double t) const;

 private:
  double grid(long i) const { return a_ + double(i) * every_; }  // the regular time i

  double a_ = 0.0, every_ = 0.0;
  long last_ = 0;                      // the regular times are i = 1 … last_ (0 without every)
  std::vector<double> extra_;          // the irregular times kept, ascending (t_start first)
  std::vector<std::size_t> extra_at_;  // their indices in the merged sequence
  std::vector<long> dropped_;          // regular indices dropped (ascending), minus their rank
  std::size_t size_ = 0;
};

// A run of consecutive sample times handed to an integrator (ascending): a range of a
// SampleGrid, or of a vector (tests). Views; the grid or vector must outlive it.
class SampleTimes {
 public:
  SampleTimes() = default;
  SampleTimes(const std::vector<double>& v) : data_(v.data()), size_(v.size()) {}  // NOLINT
  SampleTimes(const SampleGrid& g, std::size_t first, std::size_t last)
      : grid_(&g), first_(first), size_(last > first ? last - first : 0) {}

  std::size_t size() const { return size_; }
  bool empty() const { return size_ == 0; }
  double operator[](std::size_t i) const { return grid_ ? (*grid_)[first_ + i] : data_[i]; }

  class iterator {
   public:
    using iterator_category = std::input_iterator_tag;
    using value_type = double;
    using difference_type = std::ptrdiff_t;
    using pointer = const double*;
    using reference = double;
    iterator(const SampleTimes* s, std::size_t i) : s_(s), i_(i) {}
    double operator*() const { return (*s_)[i_]; }
    iterator& operator++() {
      ++i_;
      return *this;
    }
    bool operator==(const iterator& o) const { return i_ == o.i_; }
    bool operator!=(const iterator& o) const { return i_ != o.i_; }

   private:
    const SampleTimes* s_;
    std::size_t i_;
  };
  iterator begin() const { return {this, 0}; }
  iterator end() const { return {this, size_}; }

 private:
  const SampleGrid* grid_ = nullptr;
  const double* data_ = nullptr;
  std::size_t first_ = 0, size_ = 0;
};

}  // namespace ukdyn::detail
