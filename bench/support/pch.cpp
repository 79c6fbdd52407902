// SPDX-License-Identifier: BSD-3-Clause
// The translation unit that builds the benchmarks' precompiled header (support/pch.hpp).
#include "support/pch.hpp"

int main() { return 0; }
