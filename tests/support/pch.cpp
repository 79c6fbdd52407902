// SPDX-License-Identifier: BSD-3-Clause
// The translation unit that builds the tests' precompiled header (support/pch.hpp).
#include "support/pch.hpp"
