# SPDX-License-Identifier: BSD-3-Clause
# ukdyn_register_cases(PROGRAM TIMEOUT [COST]): registers a GoogleTest program's cases with CTest
# (the test programs of tests/ and app/). TIMEOUT: of each case, in seconds. COST (with
# UKDYN_TEST_SHARDS > 0 only): about the seconds the program's cases take under CI's sanitizers
# (default 5), so that CTest, which starts the costliest first when it has no times of its own
# (a fresh clone), does not leave a long program for last.
include(GoogleTest)

# How CTest runs a program's test cases (UKDYN_TEST_SHARDS):
# - 0 (the default): every case is a CTest test of its own, in a process of its own
#   (gtest_discover_tests: `ctest -R Suite.Case` runs one case; the program lists its cases when
#   it is linked).
# - N > 0: every program's cases run in one process, CTest test `<program>`, and ukdyn_tests' in N
#   processes, `ukdyn_tests/<k>of<N>` (GoogleTest's sharding: case i runs in shard i mod N). CI's
#   sanitizer build: an instrumented process costs about 0.7 CPU s to start and end (its shadow
#   memory, the leak check at exit), 800 of the suite's ~1,500 CPU s when each of its 1,150 cases
#   had a process (bench/RESULTS.md, "CI time, fifth cut"). GTEST_FILTER in the environment
#   leaves cases out (.ci/run: .ci/sanitizer-skip.txt). A case that hangs fails by its process's
#   TIMEOUT (1800 s).
set(UKDYN_TEST_SHARDS 0 CACHE STRING
    "0: each test case a CTest test (default); N > 0: each test program one CTest test, ukdyn_tests N")
function(ukdyn_register_cases name timeout)
  if(UKDYN_TEST_SHARDS GREATER 0)
    set(cost 5)
    if(ARGC GREATER 2)
      set(cost ${ARGV2})
    endif()
    set(shards 1)
    if(name STREQUAL "ukdyn_tests")
      set(shards ${UKDYN_TEST_SHARDS})
      math(EXPR cost "${cost} / ${shards}")
    endif()
    math(EXPR last "${shards} - 1")
    foreach(k RANGE ${last})
      if(shards EQUAL 1)
        set(test ${name})
      else()
        set(test ${name}/${k}of${shards})
      endif()
      add_test(NAME ${test} COMMAND ${name})
      set_tests_properties(${test} PROPERTIES TIMEOUT 1800 COST ${cost}
                                              ENVIRONMENT "GTEST_TOTAL_SHARDS=${shards};GTEST_SHARD_INDEX=${k}")
    endforeach()
  else()
    gtest_discover_tests(${name} DISCOVERY_TIMEOUT 60 PROPERTIES TIMEOUT ${timeout})
  endif()
endfunction()
