// SPDX-License-Identifier: BSD-3-Clause
// Counts heap allocations made by this process while counting is on (malloc interposition;
// see alloc_counter.cpp). Not usable under AddressSanitizer, which owns malloc itself.
#pragma once

namespace ukdyn::testing {

/// Starts counting from zero.
void start_counting_allocations();
/// Stops counting and returns the number of allocations since the start.
long stop_counting_allocations();

}  // namespace ukdyn::testing
