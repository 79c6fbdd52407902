// The translation unit that builds the tests' precompiled header (support/pch.hpp).
#include "support/pch.hpp"
